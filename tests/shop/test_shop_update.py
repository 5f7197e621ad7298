"""``toolpoint update``: the forward model against zoa_limits, the sampler against quadrature, calibration of the
bands out of sample, contradictory tables, the files, the library adapter, a virtual campaign."""

import json
import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from toolpoint.cli.main import main
from toolpoint.errors import InputError
from toolpoint.shop.campaign import virtual_campaign
from toolpoint.shop.model import ModalPrior, cornelius_2024, limit_at_speeds, receptance
from toolpoint.shop.prior import prior_from_library, read_modal_prior
from toolpoint.shop.update import (LABEL_OFFSET, OWN_MIN_ESS, TestCut, _band_levels, _own_temper, _p_chatter_map,
                                   _quantiles_at, log_likelihood, read_test_cuts, update)
from toolpoint.stability.zoa_batch import zoa_limits

# the command line's tests of parsing, files and messages run the cheaper zero-order model (the default is "sdm":
# test_the_example_session_is_the_cuts_update_proposed runs it)
UPDATE_ZOA = ["update", "--forward", "zoa"]


def test_limit_at_speeds_matches_zoa_limits_on_two_modes():
    """Second method: the lobe crossings at single speeds vs zoa_limits' interpolated lobes (same K_t, K_r)."""
    pr = replace(cornelius_2024(0.15), sigma_kt=0.0, sigma_kr=0.0)
    th = pr.sample(40, np.random.default_rng(0)).theta
    f = pr.freq_grid()
    rpm = np.array([6100.0, 9000.0, 13000.0, 17500.0, 21000.0])
    a, fc = limit_at_speeds(pr, th, rpm, f)
    ref = zoa_limits(f, receptance(pr, th, f), pr.cutting, rpm, subdivide=16)
    np.testing.assert_allclose(a, ref, rtol=5e-3)
    # the chatter frequency lies near a mode, above it (the ZOA's chatter is on the rising phase side)
    fn = th[:, :2]
    near = np.min(np.abs(fc[:, :, None] / fn[:, None, :] - 1), axis=2)
    assert np.all(near < 0.25)


def test_receptance_is_the_sum_of_mass_spring_dampers():
    """Closed form: Φ(ω) = Σ 1 / (m (ω_n² − ω² + 2 i ζ ω_n ω)), m = k / ω_n², per sample of a three-mode prior."""
    from toolpoint.shop.model import example_tool

    pr = example_tool(0.15)
    th = pr.sample(25, np.random.default_rng(4)).theta
    f = pr.freq_grid()
    M = pr.modes
    w, wn = 2 * np.pi * f[None, None, :], 2 * np.pi * th[:, :M, None]
    m, zeta = th[:, M:2 * M, None] / wn ** 2, th[:, 2 * M:3 * M, None]
    ref = (1 / (m * (wn ** 2 - w ** 2 + 2j * zeta * wn * w))).sum(axis=1)
    np.testing.assert_allclose(receptance(pr, th, f), ref, rtol=1e-11)


def _kt_only(sig=0.2):
    return replace(cornelius_2024(0.1), sigma_freq=(0.0, 0.0), sigma_stiffness=(0.0, 0.0), sigma_damping=(0.0, 0.0),
                   sigma_kt=sig, sigma_kr=0.0)


def test_growth_rate_matches_the_semi_discretisation():
    """κ = Re ∂s/∂ln a of the zero-order characteristic equation against a second method: the SDM's spectral radius
    ρ per tooth period T just past the SDM limit, ln ρ / (T ln(a / a_lim)) at a = 1.05 a_lim. Where both methods
    put the limit on the same lobe (Cornelius case, each mode's pocket, 12000 and 17000 rpm: chatter at 1268 / 1275
    Hz and 1755 / 1758 Hz, κ 352 and 310 /s against the SDM's 350 and 329 /s) they agree within 35 %; a lightly
    damped mode grows ~ζω_n. (15000 rpm, asked here before, is where the lobes of the two modes meet: the ZOA's
    limit is on the 1243 Hz mode, the SDM's on the 1747 Hz one, κ 506 against 333 /s. It passed while the SDM's
    steps, sized for the ZOA's 1374 Hz there, left the other mode unresolved and read 375 /s.)"""
    from toolpoint.shop.model import growth_rate, sdm_limits
    from toolpoint.stability import sdm_spectral_radius

    pr = cornelius_2024(0.1)
    th = pr.theta(np.zeros((1, pr.sigma.size)))
    rpm = np.array([12000.0, 17000.0])
    _, fc = limit_at_speeds(pr, th, rpm)
    kap = growth_rate(pr, th, rpm, fc)[0]
    mm, cut = pr.tool(th[0])
    a_sdm, fc_sdm = sdm_limits(pr, th[0], rpm)
    assert fc_sdm == pytest.approx(fc[0], rel=0.02)  # the same lobe
    rho = sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=1.05 * a_sdm)
    ref = np.log(rho) / (60.0 / (rpm * cut.teeth) * np.log(1.05))
    assert np.all(np.abs(kap / ref - 1) < 0.35), (kap, ref)
    # one lightly damped mode (ζ = 0.5 %, 750 Hz), chatter between the harmonics: κ ≈ ζ ω_n within a factor 2
    one, t1 = _one_slow_mode()
    t1 = t1[None, :]
    r1 = np.array([14000.0])
    _, f1 = limit_at_speeds(one, t1, r1)
    k1 = growth_rate(one, t1, r1, f1)[0, 0]
    assert 0.5 < k1 / (0.005 * 2 * np.pi * 750) < 2, k1


@pytest.mark.slow  # ~2 s: full SDM searches (the fast tier kept under 3 min)
def test_reference_ratios_started_near_the_first_agree_with_the_full_search():
    """The SDM/ZOA ratios of the reference samples after the first (bracketed from the first's ratio by
    sdm_limit_near) against each sample's own upward SDM search at every speed (sdm_limits, over the same speeds):
    within 1 % in ln a at the grid and at the cut speeds, also on the example tool's three modes."""
    from toolpoint.shop.model import example_tool, sdm_limits
    from toolpoint.shop.update import _limits, _sdm_log_ratio

    for pr, grid in ((cornelius_2024(0.1), np.linspace(9000.0, 21000.0, 25)),
                     (example_tool(), np.linspace(14000.0, 26000.0, 13))):
        f = pr.freq_grid()
        th = pr.theta(np.random.default_rng(3).standard_normal((3, pr.sigma.size)) * (pr.sigma > 0))
        rpm_c = np.array([grid[4] * 1.013, grid[8]])
        lr_c, lr_g = _sdm_log_ratio(pr, th, rpm_c, grid, f)
        zg, zc = _limits(pr, th, f, grid), limit_at_speeds(pr, th, rpm_c, f)[0]
        speeds = np.unique(np.r_[grid, rpm_c])  # the full search's resolution follows its speed range
        for i in range(3):
            full = sdm_limits(pr, th[i], speeds)[0]
            ref_g = np.log(full[np.searchsorted(speeds, grid)] / zg[i])
            ref_c = np.log(full[np.searchsorted(speeds, rpm_c)] / zc[i])
            assert np.all(np.isfinite(ref_g)) and np.max(np.abs(lr_g[i] - ref_g)) < 0.01, (i, lr_g[i] - ref_g)
            assert np.max(np.abs(lr_c[i] - ref_c)) < 0.01, (i, lr_c[i], ref_c)


def test_the_label_growth_moves_the_boundary_by_g_over_kappa_t():
    """log_likelihood's growth term: a stable label at a = a_lim e^x has P = ε + (1 − 2ε) Φ((G / (κ t) − x) / w),
    t the cut's ``duration_s`` or ``cut_duration_s``; the term is capped at 0.5 (a cut too short to hear chatter)."""
    from scipy.stats import norm

    from toolpoint.shop.model import growth_rate

    pr = cornelius_2024(0.1)
    th = pr.theta(np.zeros((1, pr.sigma.size)))
    rpm = 12000.0
    a, fc = limit_at_speeds(pr, th, [rpm])
    kap = growth_rate(pr, th, [rpm], fc)[0, 0]
    eps, w, x, g = 0.002, 0.05, 0.03, 3.0
    for dur, kw in ((0.5, {}), (None, {"cut_duration_s": 0.2}), (1e-3, {})):
        t = kw.get("cut_duration_s", dur)
        cut = [TestCut(rpm, float(a[0, 0] * np.exp(x)), True, duration_s=dur)]
        got = np.exp(log_likelihood(pr, th, cut, label_noise=eps, label_growth=g, boundary_width=w, **kw)[0])
        shift = min(g / (kap * t), 0.5)
        assert got == pytest.approx(eps + (1 - 2 * eps) * norm.cdf((shift - x) / w), rel=1e-6), (dur, kw)
    assert np.exp(log_likelihood(pr, th, cut, label_noise=eps, boundary_width=w)[0]) == \
        pytest.approx(eps + (1 - 2 * eps) * norm.cdf(-x / w), rel=1e-6)  # G = 0: no shift
    # the default boundary width is update's (BOUNDARY_WIDTH), the same closed form
    from toolpoint.shop.update import BOUNDARY_WIDTH
    assert np.exp(log_likelihood(pr, th, cut, label_noise=eps)[0]) == \
        pytest.approx(eps + (1 - 2 * eps) * norm.cdf(-x / BOUNDARY_WIDTH), rel=1e-6)


def _one_slow_mode():
    """One lightly damped mode (750 Hz, ζ 0.5 %, k 2e7 N/m) on the Cornelius cut, nothing uncertain but δ and G."""
    pr = cornelius_2024(0.1)
    one = ModalPrior((750.0,), (2e7,), (0.005,), (0.0,), (0.0,), (0.0,), pr.cutting, 0.0, 0.0)
    return one, one.theta(np.zeros((1, 5)))[0]


@pytest.mark.slow
def test_the_label_growth_against_the_time_domain_a_longer_cut_hears_slow_chatter():
    """The label-growth model (``update``'s ``label_growth``) against a second method, the time domain: on one lightly
    damped mode (ζ 0.5 %, 750 Hz, κ ≈ ζω_n ≈ 24 /s) at 17000 rpm, 5 % past the SDM limit, chatter grows as e^{κ x t}.
    The simulated shop's usual cut (250 revolutions, 0.88 s: growth ≈ e^1) sounds stable; a cut of
    t = G̃ / (0.05 κ) ≈ 2.1 s (growth e^G̃ = e^2.5) is heard as chatter at the mode. On a well-damped lobe the same
    0.88 s cut hears chatter 1–3 % past the limit (``docs/design/shop.md``). Seeds 0 and 1 (2026-11-27: 3/3 seeds
    each way; at 1.1 × the limit the short cut hears it too). ~35 s."""
    from toolpoint.shop.campaign import simulated_shop
    from toolpoint.shop.model import growth_rate, sdm_limits

    one, th = _one_slow_mode()
    rpm = 17000.0
    _, fc = limit_at_speeds(one, th[None, :], [rpm])
    kap = growth_rate(one, th[None, :], [rpm], fc)[0, 0]
    assert 0.5 < kap / (0.005 * 2 * np.pi * 750.0) < 2, kap
    t = 2.5 / (0.05 * kap)
    a = 1.05 * sdm_limits(one, th, [rpm])[0][0]
    shop = simulated_shop(one)
    for seed in (0, 1):
        short = shop(th, rpm, a, np.random.default_rng(seed))
        long = shop(th, rpm, a, np.random.default_rng(seed), duration_s=t)
        assert short.stable and short.duration_s == pytest.approx(250 * 60 / rpm), (seed, short)
        assert long.duration_s == pytest.approx(t, abs=60 / rpm), (seed, long)
        assert not long.stable and long.chatter_hz == pytest.approx(750.0, rel=0.01), (seed, long)


@pytest.mark.slow  # ~3 s: a CLI update and time-domain cuts (the fast tier kept under 3 min)
def test_the_next_cut_lasts_long_enough_for_slow_chatter_to_be_heard(tmp_path, capsys):
    """The next cut's duration with ``update``'s ``audible_margin`` 0.05: t = G̃ / (κ₂₅ · 0.05) at its speed, so
    chatter 5 % past the limit grows by e^G̃ within it — the duration the time-domain test above hears (on one 750 Hz
    mode of ζ 0.5 %, κ ≈ ζω_n: about 2 s against a 1 s default; speeds 16000–18000 rpm, between its pockets — at a
    pocket's peak the chatter sits off the resonance and grows at ~1000 /s). Never shorter than the cuts so far,
    never lengthened past the cap; a well-damped tool's cuts (Cornelius, κ ≈ 400 /s) keep the default; 0 proposes
    the cuts' own length. The default margin, 0.025 (since 2026-12-01), asks for twice as long as 0.05."""
    from toolpoint.shop.model import growth_rate

    one, th = _one_slow_mode()
    kw = dict(rng=np.random.default_rng(0), n_samples=100, lobe_samples=60, forward="zoa",
              rpm_grid=np.linspace(16000.0, 18000.0, 21), audible_margin=0.05)
    nc = update(one, [], **kw).next_cut
    _, fc = limit_at_speeds(one, th[None, :], [nc["rpm"]])
    kap = growth_rate(one, th[None, :], [nc["rpm"]], fc)[0, 0]
    assert 0.5 < kap / (0.005 * 2 * np.pi * 750.0) < 2, kap
    assert nc["growth_rate_p25_per_s"] == pytest.approx(kap, rel=1e-9)  # one θ: every sample's κ
    assert nc["duration_s"] == pytest.approx(2.5 / (kap * 0.05), rel=1e-9) and nc["duration_s"] > 1.5
    assert nc["duration_by_growth"] and nc["revolutions"] == math.ceil(nc["duration_s"] * nc["rpm"] / 60)
    assert update(one, [], max_cut_duration_s=1.2, **dict(kw, rng=np.random.default_rng(0))).next_cut[
        "duration_s"] == pytest.approx(1.2)
    off = update(one, [], **dict(kw, rng=np.random.default_rng(0), audible_margin=0.0)).next_cut
    assert off["duration_s"] == 1.0 and not off["duration_by_growth"]
    dflt = update(one, [], **{k: v for k, v in dict(kw, rng=np.random.default_rng(0)).items() if k != "audible_margin"})
    assert dflt.next_cut["duration_s"] == pytest.approx(2.5 / (dflt.next_cut["growth_rate_p25_per_s"] * 0.025),
                                                        rel=1e-9) and 3.0 < dflt.next_cut["duration_s"] < 5.0
    # cuts of 8 s so far: the next lasts as long (the 5 s cap bounds the lengthening, not the cuts made)
    cut = TestCut(nc["rpm"], 0.5 * nc["depth_m"], True, duration_s=8.0)
    assert update(one, [cut], **dict(kw, rng=np.random.default_rng(0))).next_cut["duration_s"] == pytest.approx(8.0)
    corn = update(cornelius_2024(0.1), [], **dict(kw, rng=np.random.default_rng(0), rpm_grid=None)).next_cut
    assert corn["duration_s"] == 1.0 and not corn["duration_by_growth"] and corn["growth_rate_p25_per_s"] > 200
    with pytest.raises(InputError, match="audible_margin"):
        update(one, [], **dict(kw, audible_margin=-0.1))
    # the CLI says it, and --max-cut-duration caps it
    toml = tmp_path / "slow.toml"
    toml.write_text(PRIOR_TOML.split("[[mode]]")[0].replace("rpm_min = 5000", "rpm_min = 16000").replace(
        "rpm_max = 25000", "rpm_max = 18000") + "[[mode]]\nfreq_hz = 750\nstiffness_n_m = 2e7\ndamping = 0.005\n")
    assert main([*UPDATE_ZOA, "--prior", str(toml), "--out", str(tmp_path / "d"), "--samples", "100",
                 "--audible-margin", "0"]) == 0
    assert "for at least 1.0 s" in capsys.readouterr().out  # margin 0: as long as the cuts so far (none: 1 s)
    assert main([*UPDATE_ZOA, "--prior", str(toml), "--out", str(tmp_path / "e"), "--samples", "100"]) == 0
    assert float(capsys.readouterr().out.split("for at least ")[1].split(" s")[0]) > 3.0  # the default, 0.025
    assert main([*UPDATE_ZOA, "--prior", str(toml), "--out", str(tmp_path / "o"), "--samples", "100",
                 "--audible-margin", "0.05"]) == 0
    printed = capsys.readouterr().out
    assert "s (" in printed and "rev: chatter grows slowly there)" in printed, printed
    assert float(printed.split("for at least ")[1].split(" s")[0]) > 1.5
    assert "and a shorter cut would sound stable" in (tmp_path / "o" / "report.html").read_text()
    assert main([*UPDATE_ZOA, "--prior", str(toml), "--out", str(tmp_path / "p"), "--samples", "100",
                 "--audible-margin", "0.05", "--max-cut-duration", "1.2"]) == 0
    assert "for at least 1.2 s" in capsys.readouterr().out


def test_smc_posterior_matches_quadrature_on_one_parameter():
    """Only K_t uncertain: the exact posterior on a fine grid of ln K_t vs the SMC samples' quantiles."""
    pr = _kt_only()
    cuts = [TestCut(20000.0, 0.55e-3, True), TestCut(20000.0, 0.75e-3, False, 1290.0), TestCut(9000.0, 0.5e-3, True)]
    zg = np.linspace(-5, 5, 2001)
    zz = np.zeros((zg.size, pr.sigma.size))
    zz[:, -2] = zg
    lp = -0.5 * zg ** 2 + log_likelihood(pr, pr.theta(zz), cuts)
    w = np.exp(lp - lp.max())
    cdf = np.cumsum(w) / w.sum()
    exact = np.interp([0.05, 0.5, 0.95], cdf, zg)
    post = update(pr, cuts, rng=np.random.default_rng(3), n_samples=2000, lobe_samples=50, label_offset=(0, 0),
                  forward="zoa", label_growth=(0, 0))
    got = np.quantile(post.z[:, pr.sigma.size - 2], [0.05, 0.5, 0.95])
    np.testing.assert_allclose(got, exact, atol=0.08)
    assert exact[2] - exact[0] < 0.6 * 2 * 1.645  # the cuts did narrow it


@pytest.mark.slow  # 5 s: the fast tier read 175–190 s on clean clones of the shared VM (limit 3 min)
def test_smc_posterior_matches_quadrature_with_the_label_offset():
    """K_t and the label offset δ uncertain: the exact posterior of ln K_t on a 2-D grid (ln K_t × δ, the labels'
    boundary at a_lim e^δ) vs the SMC samples' — δ shifts the band down (chatter heard only above the limit) and
    widens it, since the cuts cannot tell δ from K_t."""
    pr = _kt_only()
    cuts = [TestCut(20000.0, 0.55e-3, True), TestCut(20000.0, 0.62e-3, False, 1290.0), TestCut(9000.0, 0.5e-3, True)]
    mu, sd = 0.05, 0.04
    zg, dg = np.linspace(-5, 5, 161), np.linspace(-4, 4, 61)
    zk, zd = (g.ravel() for g in np.meshgrid(zg, dg))  # (ln K_t, δ) coordinates, one likelihood call
    zz = np.zeros((zk.size, pr.sigma.size))
    zz[:, -2] = zk
    lp = -0.5 * (zk ** 2 + zd ** 2) + log_likelihood(pr, pr.theta(zz), cuts, label_offset=mu + sd * zd)
    w = np.exp(lp - lp.max()).reshape(dg.size, zg.size).sum(axis=0)  # marginal over δ (rows), on the ln K_t grid
    cdf = np.cumsum(w) / w.sum()
    exact = np.interp([0.05, 0.5, 0.95], cdf, zg)
    post = update(pr, cuts, rng=np.random.default_rng(3), n_samples=2000, lobe_samples=50, label_offset=(mu, sd),
                  forward="zoa", label_growth=(0, 0))
    got = np.quantile(post.z[:, pr.sigma.size - 2], [0.05, 0.5, 0.95])
    np.testing.assert_allclose(got, exact, atol=0.08)
    none = update(pr, cuts, rng=np.random.default_rng(3), n_samples=2000, lobe_samples=50, label_offset=(0, 0),
                  forward="zoa", label_growth=(0, 0))
    j = int(np.argmin(np.abs(post.rpm - 20000)))
    # K_t lower (a higher limit) with δ = 0 than with δ ≈ 0.05: the limit at the cut speed moves down by about e^-μ
    ratio = post.limit_q_m[1, j] / none.limit_q_m[1, j]
    assert np.exp(-mu - 0.03) < ratio < np.exp(-mu + 0.03)
    q = post.parameter_quantiles()["label_offset_ln"]
    np.testing.assert_allclose(q[0], (mu - 1.645 * sd, mu, mu + 1.645 * sd), atol=1e-3)


@pytest.mark.slow
@pytest.mark.first
def test_bands_are_calibrated_out_of_sample():
    """Truths drawn from the prior, three cuts at random speeds and depths labelled by the truth: the posterior
    5–95 % band of the limit holds the true limit at a random speed about 90 % of the time."""
    pr = cornelius_2024(0.12)
    rng = np.random.default_rng(11)
    inside = []
    for _ in range(40):
        truth = pr.theta(rng.standard_normal((1, pr.sigma.size)))
        rpm = rng.uniform(5000, 25000, 3)
        a_true, fc = limit_at_speeds(pr, truth, rpm)
        depth = a_true[0] * np.exp(rng.normal(0, 0.3, 3))
        cuts = [TestCut(r, d, bool(d < a), None if d < a else float(f))
                for r, d, a, f in zip(rpm, depth, a_true[0], fc[0])]
        post = update(pr, cuts, rng=rng, forward="zoa", n_samples=500, lobe_samples=200,
                      rpm_grid=np.linspace(5000, 25000, 40))
        g = rng.integers(40)
        truth_lim = zoa_limits(pr.freq_grid(), receptance(pr, truth, pr.freq_grid()) * truth[0, 6] / 2003e6,
                               replace(pr.cutting, radial_ratio=float(truth[0, 7])), post.rpm[g:g + 1])[0, 0]
        inside.append(post.limit_q_m[0, g] <= truth_lim <= post.limit_q_m[2, g])
    assert 0.78 <= np.mean(inside) <= 0.99


def test_a_missed_chatter_rate_weakens_stable_labels_only():
    """``miss_rate`` m: a stable label far above a sample's limit keeps likelihood ε + m(1 − ε) (closed form), a
    chatter label there (1 − m)(1 − ε), a stable label far below 1 − ε + m ε. One stable cut at 1.3 × the prior's
    median limit lifts the posterior's band less with m = 0.2 than without; a bad m is refused."""
    pr = cornelius_2024(0.1)
    rpm = 12000.0
    th = pr.theta(np.zeros((1, pr.sigma.size)))
    a0 = float(limit_at_speeds(pr, th, [rpm])[0][0, 0])
    eps, m = 0.002, 0.2
    far_above = [TestCut(rpm, 3 * a0, True)], [TestCut(rpm, 3 * a0, False)]
    ls = log_likelihood(pr, th, far_above[0], label_noise=eps, miss_rate=m)
    lc = log_likelihood(pr, th, far_above[1], label_noise=eps, miss_rate=m)
    assert np.exp(ls) == pytest.approx(eps + m * (1 - eps), rel=1e-6)
    assert np.exp(lc) == pytest.approx((1 - m) * (1 - eps), rel=1e-6)
    far_below = log_likelihood(pr, th, [TestCut(rpm, a0 / 3, True)], label_noise=eps, miss_rate=m)
    assert np.exp(far_below) == pytest.approx(1 - eps + m * eps, rel=1e-6)
    cut = [TestCut(rpm, 1.3 * a0, True)]
    q = {mr: update(pr, cut, rng=np.random.default_rng(0), forward="zoa", n_samples=400, lobe_samples=200,
                    rpm_grid=[rpm], miss_rate=mr, label_offset=(0, 0), label_growth=(0, 0)).limit_q_m[:, 0]
         for mr in (0.0, m)}
    assert q[0.0][0] > 1.2 * a0 and q[m][0] < q[0.0][0] and q[m][1] < q[0.0][1], q
    with pytest.raises(InputError, match="miss_rate|0, 1"):
        update(pr, cut, rng=np.random.default_rng(0), forward="zoa", n_samples=50, miss_rate=1.0)
    for w in (0.0, -0.03, float("nan"), 0.9):  # the boundary width, likewise
        with pytest.raises(InputError) as e:
            update(pr, cut, rng=np.random.default_rng(0), forward="zoa", n_samples=50, boundary_width=w)
        assert e.value.field == "boundary_width", w


def test_the_recommended_speed_held_at_a_cut_speed_within_its_margin():
    """``cut_speed_margin`` s: a speed within ±0.5 % of a cut is recommended where its n · a₀₅ is at least (1 − s) of
    the best. One stable cut 1.5 % under the prior's recommended speed, 300-sample zero-order updates on a 0.5 % grid:
    with s = 0 the recommendation is that without the option (same draws); the cut speed removes 9 % less than the
    best here, so 0.03 keeps the best and 0.5 takes the cut speed (``at_cut_speed``); bad shares are refused."""
    pr = cornelius_2024(0.1)
    grid = 12000 * 1.005 ** np.arange(-40, 41)
    kw = dict(forward="zoa", n_samples=300, lobe_samples=200, rpm_grid=grid)
    r0 = update(pr, [], rng=np.random.default_rng(0), **kw).recommended["rpm"]
    rc = 0.985 * r0
    a = float(limit_at_speeds(pr, pr.theta(np.zeros((1, pr.sigma.size))), [rc])[0][0, 0])
    cuts = [TestCut(rc, 0.7 * a, True)]
    base = update(pr, cuts, rng=np.random.default_rng(1), **kw).recommended
    got = {s: update(pr, cuts, rng=np.random.default_rng(1), cut_speed_margin=s, **kw) for s in (0.0, 0.03, 0.5)}
    assert got[0.0].recommended == base and not base["at_cut_speed"] and abs(base["rpm"] / rc - 1) > 0.005
    best = np.nanmax(got[0.5].rpm * got[0.5].limit_q_m[0])
    ratio = {s: p.recommended["rpm"] * p.recommended["limit_p05_m"] / best for s, p in got.items()}
    assert got[0.03].recommended["rpm"] == base["rpm"] and ratio[0.03] == pytest.approx(1.0)
    rec = got[0.5].recommended
    assert rec["at_cut_speed"] and abs(rec["rpm"] / rc - 1) <= 0.005 and 0.5 <= ratio[0.5] < 0.97, (rec, ratio)
    for s in (-0.01, 0.6, float("nan")):
        with pytest.raises(InputError) as e:
            update(pr, cuts, rng=np.random.default_rng(0), forward="zoa", n_samples=50, cut_speed_margin=s)
        assert e.value.field == "cut_speed_margin", s


def test_the_next_cut_at_the_recommended_speed_only():
    """``next_speeds`` = 0: the ``info`` rule proposes the next cut at the recommended speed; with the default 6 it may
    take a neighbouring productive speed (here it does, for at least one of three cut tables); bad counts refused."""
    pr = cornelius_2024(0.1)
    grid = 12000 * 1.005 ** np.arange(-40, 41)
    kw = dict(forward="zoa", n_samples=300, lobe_samples=200, rpm_grid=grid)
    r0 = update(pr, [], rng=np.random.default_rng(0), **kw).recommended["rpm"]
    a = float(limit_at_speeds(pr, pr.theta(np.zeros((1, pr.sigma.size))), [r0])[0][0, 0])
    moved = []
    for cuts in ([TestCut(r0, 0.6 * a, True)], [TestCut(r0, 0.6 * a, True), TestCut(r0, 0.7 * a, True)],
                 [TestCut(r0, 0.7 * a, True), TestCut(r0, 1.1 * a, False)]):
        one = update(pr, cuts, rng=np.random.default_rng(1), next_speeds=0, **kw)
        assert one.next_cut["rpm"] == one.recommended["rpm"], (cuts, one.next_cut)
        assert "at that speed" in one.next_cut["description"]
        six = update(pr, cuts, rng=np.random.default_rng(1), **kw)
        assert six.recommended == one.recommended  # the option moves the next cut only
        moved.append(six.next_cut["rpm"] != six.recommended["rpm"])
    assert any(moved), moved
    for k in (-1, 2.5, 51, True, float("nan")):
        with pytest.raises(InputError) as e:
            update(pr, [], rng=np.random.default_rng(0), forward="zoa", n_samples=50, next_speeds=k)
        assert e.value.field == "next_speeds", k


def test_a_chatter_frequency_read_anywhere_says_nothing():
    """``freq_outlier`` = 1: every frequency is an outlier, so a chattering cut's frequency adds a constant to every
    sample's log-likelihood and the posterior is the one without it (the same draws: tempering sees only the
    differences); with the default share 0.05 a frequency on one sample's lobe and far from another's favours the
    first."""
    pr = cornelius_2024(0.1)
    rpm = 12000.0
    z = np.zeros((2, pr.sigma.size))
    z[1, :pr.modes] = 2.5  # the second sample's modes ~28 % higher: its lobes' frequencies far from the first's
    th = pr.theta(z)
    a0, fc = limit_at_speeds(pr, th[:1], [rpm])
    a, f = float(a0[0, 0]), float(fc[0, 0])
    with_f, without = [TestCut(rpm, 1.2 * a, False, f)], [TestCut(rpm, 1.2 * a, False)]
    d = log_likelihood(pr, th, with_f, freq_outlier=1.0) - log_likelihood(pr, th, without)
    assert d[0] == pytest.approx(d[1]) and d[0] == pytest.approx(-math.log(f))
    d5 = log_likelihood(pr, th, with_f, freq_outlier=0.05) - log_likelihood(pr, th, without)
    assert d5[0] > d5[1] + 2.0
    kw = dict(forward="zoa", n_samples=300, lobe_samples=100, rpm_grid=[rpm])
    q1 = update(pr, with_f, rng=np.random.default_rng(3), freq_outlier=1.0, **kw).limit_q_m
    q0 = update(pr, without, rng=np.random.default_rng(3), **kw).limit_q_m
    np.testing.assert_allclose(q1, q0, rtol=1e-9)
    for field, bad in (("freq_outlier", 0.0), ("freq_outlier", 1.5), ("freq_sigma", 0.0)):
        with pytest.raises(InputError, match=field):
            update(pr, with_f, rng=np.random.default_rng(0), **{field: bad}, **kw)

@pytest.mark.parametrize("tool", ["cornelius", "example"])
def test_the_own_searches_find_the_full_searchs_limit(tool):
    """``OWN_NEAR`` (steps of 0.07 in ln a, no halvings, ρ interpolated across the bracket) against the full upward
    search of ``sdm_limits`` — a different search of the same SDM — on 8 prior samples at three speeds each, from
    guesses ln sd 0.1 off: every limit found, ln error sd under 0.005 and each under 0.03 (its docstring: sd 0.002,
    max 0.028 on EM16-50), far under the likelihood's boundary width of 0.05."""
    from toolpoint.shop.model import example_tool, sdm_limits
    from toolpoint.shop.update import OWN_NEAR, _sdm_own_log_ratio

    pr, u = ((cornelius_2024(0.1), np.array([12000.0, 15000.0, 20377.0])) if tool == "cornelius" else
             (example_tool(0.15), np.array([9000.0, 14000.0, 21000.0])))
    rng = np.random.default_rng(11)
    z = rng.standard_normal((8, pr.sigma.size)) * (pr.sigma > 0)
    th = pr.theta(z)
    f = pr.freq_grid()
    full = np.array([sdm_limits(pr, t, u, chatter=False)[0] for t in th])
    lr_full = np.log(full / limit_at_speeds(pr, th, u, f)[0])
    lr = _sdm_own_log_ratio(pr, z, u, f, lr_full + rng.normal(0, 0.1, lr_full.shape), near=OWN_NEAR)
    assert np.all(lr != 0)  # 0: no limit found
    err = lr - lr_full
    assert err.std() < 0.005 and np.abs(err).max() < 0.03, err


def test_the_label_growth_read_from_each_samples_own_sdm():
    """``growth_by="sdm"``: each lobe sample's κ at a cut is the secant ln ρ(a) / (T ln(a / a_SDM)) from its own
    SDM limit to the cut's depth — checked against ``sdm_spectral_radius`` and ``sdm_limits`` of the same
    sample —, repeated samples get their own figures back; in the likelihood a slower κ moves the heard boundary
    further above the limit (a stable label 5 % past it is likelier), a NaN κ leaves the zero-order one;
    ``update`` refuses another value, or ``"sdm"`` without the own SDM searches, naming the field."""
    from toolpoint.shop.update import _sdm_own_log_ratio
    from toolpoint.stability import sdm_spectral_radius

    pr = cornelius_2024(0.1)
    z = np.random.default_rng(4).standard_normal((3, pr.sigma.size))
    th = pr.theta(z)
    u = np.array([12000.0, 15000.0])
    a_z = limit_at_speeds(pr, th, u)[0]
    cuts = [TestCut(12000.0, 1.1 * a_z[0, 0], False), TestCut(12000.0, 0.7 * a_z[0, 0], True),
            TestCut(15000.0, 1.01 * a_z[0, 1], True)]
    lr, kap = _sdm_own_log_ratio(pr, z, u, pr.freq_grid(), np.zeros(2), near=dict(bisections=6), cuts=cuts)
    assert kap.shape == (3, 3) and np.isfinite(kap).all() and (kap > 0).all()
    # repeated samples (resampled rows) are searched once and each row gets its own sample's figures back
    rows = [2, 0, 2, 1, 0]
    lr_r, kap_r = _sdm_own_log_ratio(pr, z[rows], u, pr.freq_grid(), np.zeros(2), near=dict(bisections=6), cuts=cuts)
    np.testing.assert_array_equal(lr_r, lr[rows])
    np.testing.assert_array_equal(kap_r, kap[rows])
    checked = 0
    for i in range(3):
        mm, c = pr.tool(th[i])
        own = a_z[i] * np.exp(lr[i])
        for k in range(2):  # the own limit: stable 1 % below, chatter 1 % above (the SDM itself)
            lo, hi = (float(np.ravel(sdm_spectral_radius(mm, mm, c, rpm=[u[k]], depth=[own[k] * e]))[0])
                      for e in (0.99, 1.01))
            assert lo < 1 < hi
        for j, cut in enumerate(cuts[:2]):  # far enough from the limit for the secant
            k = int(np.searchsorted(u, cut.rpm))
            x = math.log(cut.depth_m / own[k])
            if abs(x) >= 0.03:
                rho = float(np.ravel(sdm_spectral_radius(mm, mm, c, rpm=[cut.rpm], depth=[cut.depth_m]))[0])
                assert kap[i, j] == pytest.approx(math.log(rho) / (60.0 / (c.teeth * cut.rpm) * x), rel=0.05)
                checked += 1
    assert checked >= 4
    one = [TestCut(12000.0, 1.05 * a_z[0, 0], True)]
    kw = dict(label_offset=0.0, label_growth=2.5)
    slow, fast, none = (log_likelihood(pr, th[:1], one, kappa=np.array([[k]]), **kw) for k in (20.0, 2000.0, np.nan))
    assert slow[0] > fast[0] and none[0] == pytest.approx(log_likelihood(pr, th[:1], one, **kw)[0])
    for bad in (dict(growth_by="time"), dict(growth_by="sdm", forward="zoa"), dict(growth_by="sdm", own_sdm=False)):
        with pytest.raises(InputError, match="growth_by"):
            update(pr, one, rng=np.random.default_rng(0), **bad)

@pytest.mark.slow  # ~4 s: updates with the references' SDM (the fast tier kept under 3 min)
def test_the_sampling_reads_the_label_growth_from_the_references_sdm(monkeypatch):
    """``growth_by="sdm"`` in the sampling: the references' κ at each cut is G / (t x_b), x_b where their SDM growth
    ln ρ / T first reaches G / t — checked against ``sdm_spectral_radius`` at the SDM limit bisected on it directly;
    with one reference the ratio is that reference's own. With several, the labels' likelihood is the mean of each
    reference's (a mixture), which differs from that of their mean ratio. ``update`` then runs through with it."""
    from toolpoint.shop.model import growth_rate
    from toolpoint.shop.update import _sdm_kappa_log_ratio, _sdm_log_ratio
    from toolpoint.stability import sdm_spectral_radius

    pr = cornelius_2024(0.1)
    f = pr.freq_grid()
    th = pr.theta(np.random.default_rng(4).standard_normal((2, pr.sigma.size)))
    u = np.array([9000.0, 12000.0, 15000.0])
    g, t = 2.5, 0.1  # G / t = 25 /s: heard ≈ 0.1 past the limit on κ ≈ 300 /s
    checked = 0
    for i in range(2):
        one = th[i:i + 1]
        a_z, fc = limit_at_speeds(pr, one, u, f)
        cuts = [TestCut(r, a_z[0, k], True, duration_s=t) for k, r in enumerate(u)]
        lr_c = _sdm_log_ratio(pr, one, u, np.array([10000.0]), f)[0]
        klr = _sdm_kappa_log_ratio(pr, one, cuts, lr_c, f, g, 1.0)
        assert klr.shape == (1, u.size)
        klr = klr[0]
        kz = growth_rate(pr, one, u, fc)[0]
        mm, c = pr.tool(one[0])
        for k in range(u.size):
            assert np.isfinite(klr[k])
            rho = lambda a: float(np.ravel(sdm_spectral_radius(mm, mm, c, rpm=[u[k]], depth=[a]))[0])  # noqa: E731
            lo, hi = 0.5 * a_z[0, k], 2.0 * a_z[0, k]
            assert rho(lo) < 1 < rho(hi)
            for _ in range(40):  # the SDM limit, bisected on ρ itself
                mid = math.sqrt(lo * hi)
                lo, hi = (mid, hi) if rho(mid) < 1 else (lo, mid)
            x_b = min(g / (t * kz[k] * math.exp(klr[k])), 0.5)
            sigma = math.log(rho(lo * math.exp(x_b))) * c.teeth * u[k] / 60.0
            assert sigma == pytest.approx(g / t, rel=0.1)
            checked += 1
    assert checked == 6
    # two references of two kinds: the labels' likelihood is the mean of each one's, not that of their mean ratio
    cuts = [TestCut(12000.0, 1.08 * a_z[0, 1], True, duration_s=0.85),
            TestCut(15000.0, 1.3 * a_z[0, 2], False, duration_s=0.85)]
    kinds = np.array([[-0.5, -0.5], [2.5, 2.5]])
    kw = dict(label_offset=0.0, label_growth=2.5)
    each = np.stack([log_likelihood(pr, th, cuts, kappa_log_ratio=k, **kw) for k in kinds])  # (2, S)
    mixed = log_likelihood(pr, th, cuts, kappa_log_ratio=kinds, **kw)
    np.testing.assert_allclose(mixed, np.log(np.exp(each).mean(axis=0)), rtol=1e-12)
    assert not np.allclose(mixed, log_likelihood(pr, th, cuts, kappa_log_ratio=kinds.mean(axis=0), **kw))
    # update hands the references' ratios, one row per reference, to the sampling's likelihood
    import toolpoint.shop.update as upd

    seen = []
    real_ll = upd.log_likelihood

    def spy(*a, **k):
        if k.get("kappa_log_ratio") is not None:
            seen.append(np.shape(k["kappa_log_ratio"]))
        return real_ll(*a, **k)

    monkeypatch.setattr(upd, "log_likelihood", spy)
    post = update(pr, [TestCut(12000.0, 1.2 * a_z[0, 1], False, duration_s=0.5),
                       TestCut(12000.0, 0.8 * a_z[0, 1], True, duration_s=0.5)],
                  rng=np.random.default_rng(1), n_samples=200, lobe_samples=80, sdm_refs=2, growth_by="sdm")
    assert np.isfinite(post.recommended["depth_m"])
    assert seen and set(seen) == {(2, 2)}


def test_contradictory_table_is_refused_naming_lines(tmp_path, capsys):
    p = tmp_path / "cuts.csv"
    p.write_text("rpm,depth_mm,result\n12000,1.0,stable\n12000,0.5,chatter\n15000,0.4,stable\n")
    with pytest.raises(InputError, match="lines 2 and 3 contradict"):
        read_test_cuts(p)
    prior = tmp_path / "prior.toml"
    prior.write_text(PRIOR_TOML)
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(p), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cuts.csv" in err and "result" in err
    assert not (tmp_path / "o" / "report.html").exists()
    # within the fuzzy boundary (5 %) a stable cut above a chattering one is noise, not a contradiction
    p.write_text("rpm,depth_mm,result\n12000,0.52,stable\n12000,0.5,chatter\n")
    assert len(read_test_cuts(p)) == 2


@pytest.mark.parametrize("text,field", [
    ("rpm,depth_mm,result\n12000,-1,stable\n", "depth_mm"), ("rpm,depth_mm,result\n12000,1,maybe\n", "result"),
    ("rpm,result\n12000,stable\n", "depth_mm"), ("rpm,depth_mm,result,chatter_hz\n1e9,1,chatter,900\n", "rpm"),
    ("rpm,depth_mm,result,duration_s\n12000,1,stable,0\n", "duration_s"),
    ("rpm,depth_mm,result,duration_s\n12000,1,stable,1e5\n", "duration_s"),
    ("rpm,depth_mm,result,duration_s\n12000,1,stable,x\n", "duration_s"),
    # a stable cut's ring: it decays (σ < 0), needs its frequency, and a chattering cut has none
    ("rpm,depth_mm,result,ring_per_s,ring_hz\n12000,1,stable,30,1250\n", "ring_per_s"),
    ("rpm,depth_mm,result,ring_per_s\n12000,1,stable,-30\n", "ring_hz"),
    ("rpm,depth_mm,result,ring_hz\n12000,1,stable,1250\n", "ring_per_s"),
    ("rpm,depth_mm,result,ring_per_s,ring_hz\n12000,1,chatter,-30,1250\n", "ring_per_s"),
    ("rpm,depth_mm,result,ring_per_s,ring_hz\n12000,1,stable,x,1250\n", "ring_per_s")])
def test_bad_tables_name_the_field(tmp_path, text, field):
    p = tmp_path / "c.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=field):
        read_test_cuts(p)


def test_a_spreadsheet_s_table_reads_as_the_plain_one(tmp_path):
    """Semicolons between cells and the decimal comma (a spreadsheet's CSV in a German or French locale), capitalised
    column names: the same cuts as the plain table, not 'missing column rpm'."""
    plain, sheet = tmp_path / "plain.csv", tmp_path / "sheet.csv"
    plain.write_text("rpm,depth_mm,result,chatter_hz\n20000,0.5,stable,\n20000,0.95,chatter,1290.5\n")
    sheet.write_text("\ufeffRPM;Depth_mm;Result;Chatter_Hz\n20000;0,5;stable;\n20000;0,95;Chatter;1290,5\n",
                     encoding="utf-8")
    # and its "Unicode text": UTF-16 with its byte-order mark, tab-separated
    uni = tmp_path / "sheet.txt"
    uni.write_text("RPM\tDepth_mm\tResult\tChatter_Hz\n20000\t0,5\tstable\t\n20000\t0,95\tchatter\t1290,5\n",
                   encoding="utf-16")
    a = read_test_cuts(plain)
    for other in (sheet, uni):
        b = read_test_cuts(other)
        assert [(c.rpm, c.depth_m, c.stable, c.chatter_hz) for c in a] == \
            [(c.rpm, c.depth_m, c.stable, c.chatter_hz) for c in b], other
        assert b[1].depth_m == pytest.approx(0.95e-3) and b[1].chatter_hz == 1290.5


def test_a_spreadsheet_s_headers_with_units_read_as_the_table_s_names(tmp_path):
    """"Spindle speed [rpm]", "Depth (mm)", "Chatter [Hz]" as a shop's sheet heads its columns: the same cuts; a depth
    in µm or inches is refused naming the column (not converted by guess), and two columns of one name are refused."""
    plain, sheet = tmp_path / "plain.csv", tmp_path / "sheet.csv"
    plain.write_text("rpm,depth_mm,result,chatter_hz\n20000,0.5,stable,\n20000,0.95,chatter,1290.5\n")
    sheet.write_text("Spindle speed [rpm],Depth (mm),Verdict,Chatter [Hz]\n20000,0.5,stable,\n20000,0.95,chatter,"
                     "1290.5\n")
    a, b = read_test_cuts(plain), read_test_cuts(sheet)
    assert [(c.rpm, c.depth_m, c.stable, c.chatter_hz) for c in a] == \
        [(c.rpm, c.depth_m, c.stable, c.chatter_hz) for c in b]
    for head, match in (("rpm,depth [µm],result", "depth \\[µm\\].*give it in mm"),
                        ("rpm,Depth (in),result", "in: give it in mm"),
                        ("rpm,Speed [rpm],depth_mm,result", "'rpm' and 'Speed \\[rpm\\]' both give rpm")):
        sheet.write_text(head + "\n20000,0.5,stable,stable\n")
        with pytest.raises(InputError, match=match):
            read_test_cuts(sheet)
    # a cutting speed in m/min is not a spindle speed: not taken for one
    sheet.write_text("Speed [m/min],depth_mm,result\n300,0.5,stable\n")
    with pytest.raises(InputError, match="missing column 'rpm'"):
        read_test_cuts(sheet)


def test_a_depth_far_outside_the_prior_s_lobes_is_warned(tmp_path, capsys):
    """A depth typed in m into depth_mm (0.0005 for 0.5 mm) is 1/300 of the lobes: the label tells the posterior next
    to nothing, so the slip would pass unseen — said on stderr, naming the line; a plain table is not warned."""
    prior = tmp_path / "prior.toml"
    prior.write_text(PRIOR_TOML)
    cuts = tmp_path / "cuts.csv"
    cuts.write_text("rpm,depth_mm,result\n20000,0.0005,stable\n20000,0.5,stable\n")
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o"),
                 "--samples", "200"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cuts.csv: line 2: warning: depth 0.0005 mm" in err[0] and "in mm?" in err[0]
    cuts.write_text("rpm,depth_mm,result\n20000,0.5,stable\n")
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o2"),
                 "--samples", "200"]) == 0
    assert capsys.readouterr().err == ""


PRIOR_TOML = """name = "two modes"
[cut]
teeth = 4
tangential_coeff_n_mm2 = 2003
radial_ratio = 0.404
radial_immersion = 0.5
milling = "down"
rpm_min = 5000
rpm_max = 25000
[[mode]]
freq_hz = 1243
stiffness_n_m = 2.92e6
damping = 0.0619
[[mode]]
freq_hz = 1747
stiffness_n_m = 1.2e7
damping = 0.0288
"""


@pytest.mark.slow  # 6–7 s: three CLI updates with their plots and reports (the fast tier kept under 3 min)
def test_cli_update_writes_files_and_report(tmp_path, capsys):
    prior = tmp_path / "prior.toml"
    prior.write_text(PRIOR_TOML)
    cuts = tmp_path / "cuts.csv"
    cuts.write_text("rpm,depth_mm,result,chatter_hz\n20000,0.5,stable,\n20000,0.9,chatter,1290\n12000,0.3,stable,\n")
    out = tmp_path / "out"
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(out), "--samples", "300"]) == 0
    printed = capsys.readouterr().out
    assert "next test cut (info)" in printed
    # the band away from the cut speeds rests on the model alone (calibrated on average, not for every tool): said on
    # screen and in
    # the report, with the speeds the cuts did test
    assert "note: the band is tested by your cuts at 12000–20000 rpm; away from those speeds" in printed
    assert "tested by your cuts at 12000–20000 rpm" in (out / "report.html").read_text()
    for name in ("lobes.csv", "p_stable.csv", "parameters.csv", "update.json", "lobes.png", "report.html"):
        assert (out / name).stat().st_size > 100
    doc = json.loads((out / "update.json").read_text())
    nc = doc["next_cut"]
    assert nc["rule"] == "info" and nc["p_chatter"] <= 0.3 and not nc["stepped"]
    # how long the next cut should last: the table's cuts state none, so the default 1 s (no audible margin)
    assert nc["duration_s"] == 1.0 and nc["revolutions"] == math.ceil(nc["rpm"] / 60) and \
        f"for at least 1.0 s ({nc['revolutions']} rev)" in printed
    assert f"for at least 1.0 s ({nc['revolutions']} revolutions)" in (out / "report.html").read_text()
    assert 5000 <= doc["recommended"]["rpm"] <= 25000 and len(doc["cuts"]) == 3
    # a chattering cut's growth rate goes with it to update.json and the report, and moves the band; --no-growth
    # leaves it out of the likelihood: the same posterior as the table without it
    grown = tmp_path / "grown.csv"
    grown.write_text("rpm,depth_mm,result,chatter_hz,growth_per_s\n20000,0.5,stable,,\n20000,0.9,chatter,1290,60\n"
                     "12000,0.3,stable,,\n")
    for o, extra in (("grown", []), ("ungrown", ["--no-growth"])):
        assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(grown), "--out", str(tmp_path / o),
                     "--samples", "300", *extra]) == 0
    said = capsys.readouterr().out  # what each rate was read as, on the screen too
    assert "growth rates: line 3: 60 /s (per sample, the zero-order growth)" in said
    assert "growth rates: line 3: 60 /s (left out: --no-growth)" in said
    g = json.loads((tmp_path / "grown" / "update.json").read_text())
    assert [c["growth_per_s"] for c in g["cuts"]] == [None, 60.0, None] and doc["cuts"][1]["growth_per_s"] is None
    assert "<th>growth or ring 1/s (x: ln from the limit)</th>" in (tmp_path / "grown" / "report.html").read_text()
    assert (tmp_path / "ungrown" / "lobes.csv").read_text() == (out / "lobes.csv").read_text()
    assert (tmp_path / "grown" / "lobes.csv").read_text() != (out / "lobes.csv").read_text()
    # the zero-order forward model has no SDM check: the recommended depth is the band's 5 % limit
    assert doc["recommended"]["depth_mm"] == doc["recommended"]["limit_p05_mm"]
    assert doc["recommended"]["own_sdm_p05_mm"] is None and doc["recommended"]["own_sdm_held_out"] is None
    # --cut-speed-margin 0.5: a speed already cut (12000 or 20000 rpm, ±0.5 %) removing at least half the best's rate
    om = tmp_path / "om"
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(om), "--samples", "300",
                 "--cut-speed-margin", "0.5"]) == 0
    rm = json.loads((om / "update.json").read_text())["recommended"]
    assert rm["at_cut_speed"] and min(abs(rm["rpm"] / r - 1) for r in (12000, 20000)) <= 0.005, rm
    assert doc["recommended"]["at_cut_speed"] in (True, False)
    # --next-speeds 0: the next cut at the recommended speed itself
    on = tmp_path / "on"
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(on), "--samples", "300",
                 "--next-speeds", "0"]) == 0
    dn = json.loads((on / "update.json").read_text())
    assert dn["next_cut"]["rpm"] == pytest.approx(dn["recommended"]["rpm"], abs=0.1)  # as written: to 0.1 rpm
    assert "at that speed" in dn["next_cut"]["description"]
    html = (out / "report.html").read_text()
    assert "data:image/png;base64," in html and "src='http" not in html and "<script src" not in html
    lobes = np.genfromtxt(out / "lobes.csv", delimiter=",", names=True)
    assert np.all(lobes["p05_mm"] <= lobes["p50_mm"]) and np.all(lobes["p50_mm"] <= lobes["p95_mm"])
    # the zero-order model has no references' ratios to allow for: the band is read at 5 % and 95 %
    assert np.all(lobes["p05_level"] == 0.05) and np.all(lobes["p95_level"] == 0.95)
    # the stable cut at 20000 rpm, 0.5 mm: the posterior 5 % limit there is near or above it
    k = np.argmin(np.abs(lobes["rpm"] - 20000))
    assert lobes["p05_mm"][k] > 0.45 and lobes["p95_mm"][k] < 0.95
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o5"),
                 "--risk-after-chatter", "0.35"]) == 2
    assert "--risk-after-chatter: must be ≤ the bound before any chatter" in capsys.readouterr().err
    assert not (tmp_path / "o5").exists()
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o3"),
                 "--min-step", "-1"]) == 2
    assert "--min-step" in capsys.readouterr().err and not (tmp_path / "o3").exists()
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o4"),
                 "--min-step", "0.1", "--rule", "risk"]) == 2
    assert "min_step" in capsys.readouterr().err and not (tmp_path / "o4").exists()
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o6"),
                 "--step-only-after-creep", "--rule", "risk"]) == 2
    assert "--step-only-after-creep: only with --rule info" in capsys.readouterr().err
    assert not (tmp_path / "o6").exists()
    # --label-offset MEAN,SD: the labels' boundary e^δ above the limit. The default (0.01, 0.02) puts the band at
    # the cut speed below that of 0,0 (labels = the limit), and parameters.csv reports δ's prior and posterior
    rows = {r.split(",")[0]: r.split(",") for r in (out / "parameters.csv").read_text().splitlines()}
    mu, sd = LABEL_OFFSET
    assert rows["label_offset_ln"][1] == "ln" and [float(v) for v in rows["label_offset_ln"][2:5]] == \
        pytest.approx([mu - 1.645 * sd, mu, mu + 1.645 * sd], abs=1e-4)
    o0 = tmp_path / "o0"
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(o0), "--samples", "300",
                 "--label-offset", "0,0"]) == 0
    lobes0 = np.genfromtxt(o0 / "lobes.csv", delimiter=",", names=True)
    assert lobes0["p05_mm"][k] > lobes["p05_mm"][k], (lobes0["p05_mm"][k], lobes["p05_mm"][k])
    # --boundary-width LN: a stable label rules out limits under the cut less sharply, so the band's 5 % line at the
    # stable cut lies lower with the old 0.1-wide boundary than with the default
    ow = tmp_path / "ow"
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(ow), "--samples", "300",
                 "--label-offset", "0,0", "--boundary-width", "0.1"]) == 0
    lobes_w = np.genfromtxt(ow / "lobes.csv", delimiter=",", names=True)
    assert lobes_w["p05_mm"][k] < lobes0["p05_mm"][k], (lobes_w["p05_mm"][k], lobes0["p05_mm"][k])
    for bad in ("0.1", "0.1,x", "0.1,-0.1", "0.9,0.1", "nan,0.1"):
        capsys.readouterr()
        assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o5"),
                     "--label-offset", bad]) == 2, bad
        err = capsys.readouterr().err
        assert "--label-offset" in err and "Traceback" not in err and not (tmp_path / "o5").exists(), (bad, err)
    # --label-growth MEDIAN,SD (G: chatter is heard once grown by e^G within the cut) and --cut-duration: G's prior
    # quantiles in parameters.csv; bad values exit 2 naming the option, nothing written
    assert [float(v) for v in rows["label_growth_ln"][2:5]] == \
        pytest.approx([2.5 * np.exp(-1.645 * 0.5), 2.5, 2.5 * np.exp(1.645 * 0.5)], rel=1e-3)
    for flag, bad in (("--label-growth", "2"), ("--label-growth", "-1,0.5"), ("--label-growth", "2,x"),
                      ("--label-growth", "30,0.5"), ("--cut-duration", "0"), ("--cut-duration", "inf"),
                      ("--max-cut-duration", "0"), ("--max-cut-duration", "1e5"), ("--audible-margin", "-0.1"),
                      ("--audible-margin", "0.9"), ("--boundary-width", "0"), ("--boundary-width", "0.9"),
                      ("--boundary-width", "nan"), ("--cut-speed-margin", "-0.1"), ("--cut-speed-margin", "0.6"),
                      ("--cut-speed-margin", "nan"), ("--next-speeds", "-1"), ("--next-speeds", "2.5"),
                      ("--next-speeds", "51")):
        capsys.readouterr()
        assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(cuts), "--out", str(tmp_path / "o6"),
                     f"{flag}={bad}"]) == 2, bad
        err = capsys.readouterr().err
        assert flag in err and "Traceback" not in err and not (tmp_path / "o6").exists(), (bad, err)


@pytest.mark.slow
def test_no_step_above_stable_cuts_once_the_shop_is_noisy(tmp_path):
    """The step above the highest stable cut (proposed whatever its P(chatter)) rests on the stable labels; once a
    stable cut's record rings tightly (a noisy shop, whose labels at a pocket's top may be chatter unheard:
    ``noisy_pocket``) the risk bound alone proposes the next cut. The cuts of the step test below, the last stable
    cut with a ring read to an ln sd of 0.2 (noisy) or 1.5 (loose: a quiet shop's kick); ``noisy_pocket=None`` steps
    again. Three 300-sample zero-order updates."""
    from toolpoint.shop.prior import read_modal_prior

    (tmp_path / "prior.toml").write_text(PRIOR_TOML)
    pr = read_modal_prior(tmp_path / "prior.toml")
    base = [TestCut(20000.0, 0.5e-3, True), TestCut(12000.0, 0.3e-3, True)]
    nxt = {}
    for name, sd, npk in (("noisy", 0.2, 0.025), ("loose", 1.5, 0.025), ("off", 0.2, None)):
        last = TestCut(20678.0, 0.74e-3, True, ring_per_s=-60.0, ring_hz=1250.0, ring_ln_sd=sd)
        post = update(pr, [*base, last], rng=np.random.default_rng(4), n_samples=300, lobe_samples=150,
                      forward="zoa", noisy_pocket=npk)
        nxt[name] = (post.next_cut, post.noisy_pocket)
    assert nxt["noisy"][1] == 0.025 and nxt["loose"][1] is None and nxt["off"][1] is None
    assert not nxt["noisy"][0]["stepped"] and nxt["noisy"][0]["p_chatter"] <= 0.3, nxt["noisy"]
    for name in ("loose", "off"):
        assert nxt[name][0]["stepped"] and nxt[name][0]["p_chatter"] > 0.3, (name, nxt[name])


@pytest.mark.slow
def test_cli_update_steps_above_stable_cuts_until_the_first_chatter(tmp_path, capsys):
    """``toolpoint update`` steps ×e^--min-step above the highest stable cut near a speed while no cut has chattered,
    and not after a chatter (``--step-until-near-chatter``: not after a chatter near that speed; with
    ``--step-only-after-creep`` it is refused, exit 2). Updates of 300 samples, ~15 s CPU: the slow tier; the
    rest of the CLI in ``test_cli_update_writes_files_and_report``."""
    prior = tmp_path / "prior.toml"
    prior.write_text(PRIOR_TOML)
    # at 20678 rpm (a grid speed of this prior) the risk bound alone proposes ~0.775 mm above a stable cut at 0.74 mm
    # (+5 %): the step ×e^0.1 above it (moved to a speed within 2 % by the posterior median's ratio) is proposed
    # instead (P(chatter) 0.67 measured); after a chatter, at any speed, the risk bound's cut; --min-step 0 never steps
    base = "rpm,depth_mm,result\n20000,0.5,stable\n12000,0.3,stable\n"
    nxt = {}
    for name, rows in (("one", "20678,0.74,stable\n"), ("crept", "20678,0.70,stable\n20678,0.74,stable\n"),
                       ("chatter", "20678,0.70,stable\n20678,0.74,stable\n15000,0.9,chatter\n")):
        (tmp_path / f"{name}.csv").write_text(base + rows)
        for ms in ((), ("--min-step", "0"), ("--step-only-after-creep",), ("--step-until-near-chatter",)):
            capsys.readouterr()
            o = tmp_path / f"{name}{len(ms)}{ms[:1]}"
            assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(tmp_path / f"{name}.csv"), "--out", str(o),
                         "--samples", "300", *ms]) == 0
            nxt[name, ms[:1]] = (json.loads((o / "update.json").read_text())["next_cut"], capsys.readouterr().out)
    # --step-only-after-creep (the rule before): a step only once two stable cuts crept closer than the step, and
    # then whether a cut chattered elsewhere or not
    # --step-until-near-chatter: a chatter 27 % away in speed leaves the step
    stepping = (("one", ()), ("crept", ()), ("crept", ("--step-only-after-creep",)),
                ("chatter", ("--step-only-after-creep",)), ("one", ("--step-until-near-chatter",)),
                ("crept", ("--step-until-near-chatter",)), ("chatter", ("--step-until-near-chatter",)))
    for key, (nc, printed) in nxt.items():
        if key in stepping:
            assert nc["stepped"] and nc["p_chatter"] > 0.3, (key, nc)
            assert "a step above the highest stable cut near this speed" in printed, printed
            assert abs(nc["rpm"] / 20678 - 1) <= 0.02 and 0.74 * 1.08 < nc["depth_mm"] < 0.74 * 1.15, (key, nc)
        else:
            assert nc["p_chatter"] <= 0.3 and not nc["stepped"] and "a step above" not in printed, (key, nc)
    capsys.readouterr()
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(tmp_path / "one.csv"), "--out",
                 str(tmp_path / "both"), "--step-until-near-chatter", "--step-only-after-creep"]) == 2
    err = capsys.readouterr().err
    assert "--step-until-near-chatter" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "both").exists()


def test_modal_prior_file_errors_name_the_field(tmp_path):
    p = tmp_path / "p.toml"
    p.write_text(PRIOR_TOML.replace("damping = 0.0619", "damping = -1"))
    with pytest.raises(InputError, match="damping"):
        read_modal_prior(p)
    p.write_text(PRIOR_TOML.replace("teeth = 4", "teeth = 0"))
    with pytest.raises(InputError, match="cut.teeth"):
        read_modal_prior(p)


def test_library_adapter_reads_modes_and_cutting(tmp_path):
    """A library output's tool (npz + json as recommend.run writes them) → modes of its nominal FRF."""
    tools = tmp_path / "tools"
    tools.mkdir()
    f = np.arange(200.0, 4000.0, 1.0)
    h = sum(1 / (k * (1 - (f / fn) ** 2 + 2j * z * f / fn)) for fn, k, z in ((900, 8e6, 0.03), (2100, 2e7, 0.02)))
    hq = np.abs(h)[None, :] * np.array([0.8, 1.0, 1.25])[:, None]
    np.savez(tools / "T1.npz", freq_hz=f, frf_nominal=h, frf_abs_q=hq)
    (tools / "T1.json").write_text(json.dumps({"cutting": {"teeth": 3, "tangential_coeff": 7e8, "radial_ratio": 0.3,
                                                           "radial_immersion": 0.5, "milling": "up"}}))
    pr = prior_from_library(tmp_path, "T1")
    assert pr.modes == 2 and pr.cutting.teeth == 3 and pr.cutting.milling == "up"
    np.testing.assert_allclose(sorted(pr.freq_hz), [900, 2100], rtol=2e-3)
    assert abs(pr.sigma_stiffness[0] - np.log(1.25 / 0.8) / 3.29) < 1e-9
    assert (pr.sigma_kt, pr.sigma_kr) == (0.1, 0.05)  # an output that does not state them
    doc = json.loads((tools / "T1.json").read_text())
    (tools / "T1.json").write_text(json.dumps({**doc, "cutting_sigma_ln": {"K_t": 0.15, "K_r": 0.2}}))
    pr = prior_from_library(tmp_path, "T1")
    assert (pr.sigma_kt, pr.sigma_kr) == (0.15, 0.2)  # the library's own, as it sampled them
    assert pr.rpm_range is None  # no speed grid in the file: the modes' lobes decide
    np.savez(tools / "T1.npz", freq_hz=f, frf_nominal=h, frf_abs_q=hq, rpm=np.linspace(4000.0, 24000.0, 50))
    assert prior_from_library(tmp_path, "T1").rpm_range == (4000.0, 24000.0)  # the library row's speed range
    with pytest.raises(InputError, match="no tool 'T9'"):
        prior_from_library(tmp_path, "T9")


@pytest.mark.slow  # 3 s: the fast tier read 175–190 s on clean clones of the shared VM (limit 3 min)
def test_library_prior_is_not_surer_than_the_library(tmp_path, capsys):
    """A real ``library`` output (the shared small run): the prior update makes of each tool holds the library's
    own 5–95 % band of the limit at every speed (the adapter may add what the library does not model — the
    running spindle's frequency shift, the peak-picking — never remove what it sampled), around the same median."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recommend"))
    from test_library import small_run

    from toolpoint.recommend.library import tool_file_stem
    from toolpoint.shop.update import _limits

    out = small_run()
    for tool in ("A16", "B12"):
        lib = np.load(out / "tools" / f"{tool_file_stem(tool)}.npz")
        rpm, q = lib["rpm"], lib["limit_q_mm"] / 1e3
        pr = prior_from_library(out, tool)
        z = np.random.default_rng(0).standard_normal((400, pr.sigma.size)) * (pr.sigma > 0)
        qp = np.quantile(_limits(pr, pr.theta(z), pr.freq_grid(), rpm), [0.05, 0.5, 0.95], axis=0)
        holds = (qp[0] <= q[0] * 1.01) & (qp[2] >= q[2] * 0.99)
        assert holds.mean() >= 0.95, (tool, holds.mean())
        assert np.median(np.abs(np.log(qp[1] / q[1]))) < 0.1, tool
    # the CLI: --sigma-freq overrides the library prior's σ_f, and only a library prior's
    capsys.readouterr()  # what the shared run printed, if it ran here
    assert main([*UPDATE_ZOA, "--library", str(out), "--tool", "B12", "--sigma-freq", "0.02", "--samples", "100",
                 "--out", str(tmp_path / "u")]) == 0
    assert (tmp_path / "u" / "report.html").exists()
    # the modes it rests on, said in order of frequency (the library lists them strongest first)
    said = [float(m.split(" Hz")[0].split(": ")[-1]) for m in capsys.readouterr().out.splitlines()[0].split("; ")
            if " Hz, k " in m]
    assert len(said) == prior_from_library(out, "B12").modes and said == sorted(said), said
    assert main([*UPDATE_ZOA, "--library", str(out), "--tool", "B12", "--sigma-freq", "2", "--out",
                 str(tmp_path / "v")]) == 2


@pytest.mark.slow
def test_virtual_campaign_converges_with_few_chatters():
    """The loop on the update's own forward model (zero-order shop): converges within 8 cuts, ≤ 2 chatter."""
    pr = cornelius_2024(0.1)
    r = virtual_campaign(pr, rng=np.random.default_rng(0), forward="zoa", max_cuts=8, n_samples=400, lobe_samples=200)
    assert r.converged_after is not None and r.converged_after <= 8
    assert r.chatter_cuts <= 2
    assert r.width[-1] <= 0.2 and r.coverage[-1] >= 0.9
    # every speed is inside the band, under its 5 % limit or over its 95 %: the misses say on which side it failed
    assert np.allclose(np.add(r.coverage, r.miss_low) + np.asarray(r.miss_high), 1.0)
    assert isinstance(ModalPrior, type)


@pytest.mark.slow
def test_stable_cuts_climb_by_the_boundary_width_not_by_the_risk_quantile():
    """A truth above the prior's median (K_t / 1.4: the limit 40 % up): with the risk bound alone each stable cut
    sits at the posterior's 30 % quantile, a few % above the last one, and the band creeps (measured 2026-11-26:
    0.51 → 0.76 mm in 10 stable cuts, +1–10 % a cut, converged after 10); with ``min_step`` 0.1 (the default) a
    cut ×e^0.1 above the highest stable cut is proposed until the first chatter, and the band closes sooner
    (2026-11-29: 0.51, 0.57, 0.63, 0.70, 0.77 mm, converged after 5; after 8 with the step only above two stable
    cuts that crept, the rule before)."""
    pr = cornelius_2024(0.1)
    truth = pr.theta(np.zeros((1, pr.sigma.size)))[0]
    truth[3 * pr.modes] /= 1.4
    top, conv, runs = {}, {}, {}
    for ms in (0.0, 0.1):
        # the zero-order shop labels by the limit itself: δ = 0 known (the default prior of δ widens the band
        # by its own spread, which this test of the next-cut rule is not about)
        r = virtual_campaign(pr, rng=np.random.default_rng(3), theta_true=truth, max_cuts=9, n_samples=300,
                             forward="zoa", lobe_samples=150, min_step=ms, label_offset=(0, 0), label_growth=(0, 0))
        top[ms] = max(c.depth_m for c in r.cuts[:7] if c.stable)
        conv[ms] = np.inf if r.converged_after is None else r.converged_after
        runs[ms] = [(round(1e3 * c.depth_m, 3), c.stable) for c in r.cuts]
    assert top[0.1] >= 1.05 * top[0.0], runs
    assert conv[0.1] < conv[0.0], (conv, runs)
    # here it climbs by the step: each cut up to the first chatter at least ×e^0.1 above the highest stable cut
    # before it (up to the median's ratio between neighbouring speeds, ≤ 2 % here), and no step after a chatter
    d = runs[0.1]
    first_chatter = next((i for i, (_, ok) in enumerate(d) if not ok), len(d))
    for i in range(1, len(d)):
        st = sorted(a for a, ok in d[:i] if ok)
        if i <= first_chatter:
            assert d[i][0] >= 0.98 * np.exp(0.1) * st[-1], runs
        elif st:
            assert abs(d[i][0] / st[-1] - np.exp(0.1)) >= 2e-3, runs


def _assert_same_cut(a, b, skip=()):
    """The same proposed cut: every item equal, its floats to rounding. Two runs on the same input differed in the
    16th digit of p_chatter and expected_log_width on the minimum-version CI (NumPy 1.26; 2026-11-28, twice): the order
    of a reduction, not another proposal."""
    a = {k: v for k, v in a.items() if k not in skip}
    b = {k: v for k, v in b.items() if k not in skip}
    assert a.keys() == b.keys(), (a, b)
    assert all(a[k] == pytest.approx(b[k], rel=1e-9) if isinstance(a[k], float) else a[k] == b[k] for k in a), (a, b)


def test_the_next_cut_does_not_repeat_an_outcome_the_shop_already_has():
    """A cut no deeper than a stable one at its speed (or no shallower than a chattering one) ends as that one did;
    the likelihood, which takes each cut's fuzzy boundary as independent, would count it as news. The info rule does
    not propose one; where every candidate would be one it proposes as before and says so."""
    from toolpoint.shop.update import _next_info

    rng = np.random.default_rng(0)
    grid = np.linspace(10000, 12000, 21)
    lim = 1e-3 * np.exp(0.1 * rng.standard_normal((400, 1)) + 0.05 * rng.standard_normal((400, grid.size)))
    lim *= (1 + 0.3 * np.exp(-0.5 * ((grid - 11000) / 300) ** 2))[None, :]  # the productive speeds near 11000 rpm
    j = int(np.argmax(grid * np.quantile(lim, 0.05, axis=0)))
    args = (lim, grid, j, 0.3, 0.05, 0.002)
    free = _next_info(*args, cuts=(), skip_repeats=True)
    assert not free["repeat"]
    # a stable cut deeper than the rule's pick, at its speed (these samples are not conditioned on it): without the
    # skip the rule proposes the shallower cut there, a repeat; with it, not
    cut = TestCut(free["rpm"], 1.05 * free["depth_m"], True)
    for skip in (False, True):
        nxt = _next_info(*args, cuts=(cut,), skip_repeats=skip)
        repeat = abs(nxt["rpm"] / cut.rpm - 1) <= 0.005 and nxt["depth_m"] <= cut.depth_m
        assert repeat != skip and not nxt["repeat"] and nxt["p_chatter"] <= 0.3
    # stable cuts above the risk bound at every speed: nothing new within it; proposed as before, and said
    deep = tuple(TestCut(float(r), 2e-3, True) for r in grid)
    every = _next_info(*args, cuts=deep, skip_repeats=True)
    assert every["repeat"] and "repeats one already made" in every["description"]
    before = _next_info(*args, cuts=deep, skip_repeats=False)
    _assert_same_cut(every, before, skip=("repeat", "description"))


def test_the_step_climbs_above_stable_cuts_until_the_first_chatter():
    """Until a cut chatters the bracket has no upper side: above the highest stable cut near a speed (±2 %, its depth
    moved by the posterior median's ratio between the speeds) a step ×e^min_step is a candidate where the risk bound
    stops short of it; after any chatter, the risk bound alone. The rule before (``step_until_chatter=False``,
    ``creep_span=0.005``) stepped only above two stable cuts at one speed (±0.5 %) that crept, and missed the creep
    over neighbouring grid speeds that the whole loop showed (``docs/design/shop.md``)."""
    from toolpoint.shop.update import _next_info

    rng = np.random.default_rng(0)
    grid = 19000 * 1.006 ** np.arange(21)  # 0.6 % apart
    # the posterior piled up just above a stable cut (the truth above the prior's median): the limit at speed k
    # 0.5 mm × e^(0.01 (k − 14)) × e^|N(0, 0.15)| — its 30 % quantile only ×1.06 up, short of the step ×1.105 — and
    # the productive speeds (the rule's candidates) 15–20, not 14
    slope = np.exp(0.01 * (np.arange(grid.size) - 14))
    lim = 0.5e-3 * slope * np.exp(np.abs(0.15 * rng.standard_normal((400, 1)))
                                  + 0.002 * rng.standard_normal((400, grid.size)))
    j = 20
    args = (lim, grid, j, 0.3, 0.05, 0.002)
    kw = dict(min_step=0.1, skip_repeats=True)

    def cut(k, f=1.0, stable=True):
        return TestCut(float(grid[k]), f * 0.5e-3 * slope[k], stable)

    one = (cut(14),)
    new = _next_info(*args, cuts=one, **kw, creep_span=0.02, step_until_chatter=True)
    k = int(np.argmin(abs(grid - new["rpm"])))
    assert new["stepped"] and new["p_chatter"] > 0.3 and 15 <= k <= 17, new
    # the stable cut at 14 moved to speed k by the posterior median's ratio, then ×e^0.1
    moved = one[0].depth_m * np.median(lim[:, k]) / np.median(lim[:, 14])
    assert new["depth_m"] == pytest.approx(moved * np.exp(0.1), rel=1e-6), (new, moved)
    assert "until the first chatter" in new["description"]
    # the rule before: one stable cut brings no step
    old = _next_info(*args, cuts=one, **kw, creep_span=0.005, step_until_chatter=False)
    assert not old["stepped"] and old["p_chatter"] <= 0.3, old
    # a chatter anywhere: no step, whichever stable cuts crept
    for cuts in (one, (cut(15, 0.97), cut(15))):
        after = _next_info(*args, cuts=(*cuts, cut(0, 1.5, False)), **kw, creep_span=0.02, step_until_chatter=True)
        assert not after["stepped"] and after["p_chatter"] <= 0.3, after
    # "near": a chatter 8–10 % away in speed gives these speeds no upper side, so the step stays; one within
    # ±2 % of the stepped speed takes it away
    far = _next_info(*args, cuts=(*one, cut(0, 1.5, False)), **kw, creep_span=0.02, step_until_chatter="near")
    assert far["stepped"] and "chatters near its speed" in far["description"], far
    assert far["rpm"] == new["rpm"] and far["depth_m"] == pytest.approx(new["depth_m"]), (far, new)
    close = _next_info(*args, cuts=(*one, cut(k, 1.5, False)), **kw, creep_span=0.02, step_until_chatter="near")
    assert not close["stepped"] and close["p_chatter"] <= 0.3, close
    # two stable cuts that crept, 0.6 % apart in speed: the rule before saw no creep (±0.5 %); ±2 % sees it
    apart = (cut(14, 0.97), cut(15))
    narrow = _next_info(*args, cuts=apart, **kw, creep_span=0.005, step_until_chatter=False)
    wide = _next_info(*args, cuts=apart, **kw, creep_span=0.02, step_until_chatter=False)
    assert not narrow["stepped"] and wide["stepped"], (narrow, wide)
    # a span past 10 % of the speed is no neighbourhood: refused, naming the field, before any sampling
    for bad in (-0.01, 0.2):
        with pytest.raises(InputError, match="creep_span") as exc:
            update(cornelius_2024(0.1), one, rng=np.random.default_rng(0), creep_span=bad)
        assert exc.value.field == "creep_span"
    with pytest.raises(InputError, match="'near'") as exc:
        update(cornelius_2024(0.1), one, rng=np.random.default_rng(0), step_until_chatter="elsewhere")
    assert exc.value.field == "step_until_chatter"
    # no step at all with min_step 0
    assert not _next_info(*args, cuts=one, skip_repeats=True, min_step=0.0, step_until_chatter=True)["stepped"]


def test_table_records_are_analysed_and_contradictions_reported(tmp_path):
    import soundfile as sf

    from shop_synth import shop_record

    x, rate, *_ = shop_record(rpm=12000, teeth=4, chatter_hz=1310.0, chatter_amp=0.5, seed=8)
    sf.write(tmp_path / "c1.wav", x, int(rate), subtype="PCM_16")
    p = tmp_path / "cuts.csv"
    p.write_text("rpm,depth_mm,result,record,duration_s\n12000,0.8,,c1.wav,\n9000,0.3,stable,,3.5\n")
    cuts = read_test_cuts(p, teeth=4)
    assert not cuts[0].stable and abs(cuts[0].chatter_hz / 1310 - 1) < 0.01 and cuts[1].stable
    # how long the tool cut: from the record (its run of entry, cut and exit: 2 s) or the table's duration_s
    assert cuts[0].duration_s == pytest.approx(2.0, abs=0.15) and cuts[1].duration_s == 3.5
    p.write_text("rpm,depth_mm,result,record\n12000,0.8,stable,c1.wav\n")
    with pytest.raises(InputError, match="line 2: the table says stable, its record c1.wav says chatter"):
        read_test_cuts(p, teeth=4)
    # a record `cut` will not judge (noise: no spindle heard): the table's own label stands and says why; without a
    # label the line is refused, naming it and the record
    sf.write(tmp_path / "n.wav", np.random.default_rng(0).normal(0.0, 0.01, int(4 * rate)), int(rate),
             subtype="PCM_16")
    p.write_text("rpm,depth_mm,result,record\n12000,0.8,stable,n.wav\n")
    (c,) = read_test_cuts(p, teeth=4)
    assert c.stable and len(c.warnings) == 1 and "its record n.wav was not judged (rpm: no spindle" in c.warnings[0]
    p.write_text("rpm,depth_mm,result,record\n12000,0.8,,n.wav\n")
    with pytest.raises(InputError, match="line 2: its record n.wav was not judged: rpm: no spindle") as exc:
        read_test_cuts(p, teeth=4)
    assert exc.value.field == "record"


@pytest.mark.slow  # 3 s: the fast tier read 175–190 s on clean clones of the shared VM (limit 3 min)
def test_a_table_row_names_its_part_of_a_session_record(tmp_path):
    """A shop records a session of test cuts in one file: a row's ``start_s``/``end_s`` name its cut's part (as
    ``cut --start --end``). Before, a row could only take the whole record: two cuts at one speed gave both rows the
    record's verdict (chatter), and two speeds were refused with advice (``--start/--end``) a table cannot take."""
    import soundfile as sf

    from shop_synth import shop_record

    a, rate, *_ = shop_record(rpm=6000, teeth=4, seed=1)
    b, _, *_ = shop_record(rpm=8000, teeth=4, seed=3, chatter_hz=1234.0, chatter_amp=0.5)
    c, _, *_ = shop_record(rpm=6000, teeth=4, seed=2, chatter_hz=1234.0, chatter_amp=0.5)
    for name, x in (("session.wav", np.concatenate([a, c])), ("two.wav", np.concatenate([a, b]))):
        sf.write(tmp_path / name, 0.5 * x / np.abs(x).max(), int(rate), subtype="PCM_16")
    p = tmp_path / "cuts.csv"
    p.write_text("rpm,depth_mm,result,record,start_s,end_s\n6000,0.5,,session.wav,0,4\n6000,0.8,,session.wav,4,\n"
                 "6000,0.4,,two.wav,,4\n8000,0.7,,two.wav,4,\n")
    cuts = read_test_cuts(p, teeth=4)
    assert [c.stable for c in cuts] == [True, False, True, False]
    assert cuts[1].chatter_hz == pytest.approx(1234.0, rel=0.01) and cuts[3].chatter_hz == pytest.approx(1234.0,
                                                                                                       rel=0.01)
    assert all(c.warnings == () for c in cuts), [c.warnings for c in cuts]  # each part holds one cut
    assert [round(c.duration_s) for c in cuts] == [2, 2, 2, 2]
    # `cut --table` writes the rows, parts and all; update refuses them until the depths are filled in
    table = tmp_path / "sub" / "t.csv"
    table.parent.mkdir()
    assert main(["cut", str(tmp_path / "session.wav"), "--rpm", "6000", "--teeth", "4", "--out",
                 str(tmp_path / "s.json"), "--table", str(table)]) == 0
    rows = table.read_text().splitlines()
    assert rows[0] == "rpm,depth_mm,result,record,start_s,end_s" and len(rows) == 3
    assert rows[1].startswith("6000,,,../session.wav,0.5") and rows[2].startswith("6000,,,../session.wav,4.0")
    with pytest.raises(InputError, match="line 2: empty") as exc:
        read_test_cuts(table, teeth=4)
    assert exc.value.field == "depth_mm"
    table.write_text(rows[0] + "\n" + "\n".join(r.replace("6000,,", f"6000,{d},") for r, d in zip(rows[1:], (0.5, 0.8)))
                     + "\n")
    assert [c.stable for c in read_test_cuts(table, teeth=4)] == [True, False]
    # a record named as a recorder may name it (a comma; a leading '-' a spreadsheet would run as a formula): quoted
    # and prefixed in the table, read back as the file
    import shutil

    odd = tmp_path / "-take, 1.wav"
    shutil.copy(tmp_path / "session.wav", odd)
    beside = tmp_path / "t2.csv"
    assert main(["cut", str(odd), "--rpm", "6000", "--teeth", "4", "--out", str(tmp_path / "o.json"), "--table",
                 str(beside)]) == 0
    text = beside.read_text()
    assert "\"'-take, 1.wav\"" in text
    beside.write_text(text.replace("6000,,", "6000,0.5,", 1).replace("6000,,", "6000,0.8,", 1))
    got = read_test_cuts(beside, teeth=4)
    assert [c.stable for c in got] == [True, False] and all(c.record.startswith("-take, 1.wav (") for c in got)
    # the whole session for one row: warned, and told how to name the part
    p.write_text("rpm,depth_mm,result,record\n6000,0.5,,session.wav\n")
    (w,) = read_test_cuts(p, teeth=4)[0].warnings
    assert "session.wav: the record holds 2 cuts" in w and "start_s and end_s" in w
    # a record of two speeds without a part: refused in the table's words, naming the line and the record
    p.write_text("rpm,depth_mm,result,record\n6000,0.5,,two.wav\n")
    with pytest.raises(InputError, match=r"line 2: its record two.wav was not judged: rpm: the cut at 5\.0–7\.0 s ran "
                                         r"at another spindle speed.*its own row \(rpm; start_s, end_s: that cut with "
                                         r"its air is 4\.0–7\.5 s\)"):
        read_test_cuts(p, teeth=4)
    # the part's own refusal and contradiction name it
    p.write_text("rpm,depth_mm,result,record,start_s,end_s\n6000,0.8,stable,session.wav,4,8\n")
    with pytest.raises(InputError, match=r"line 2: the table says stable, its record session.wav \(4–8 s\) says "
                                         r"chatter at 123\d\.\d Hz"):
        read_test_cuts(p, teeth=4)
    for body, field, said in (("6000,0.5,stable,,1,3", "start_s", "line 2: a part of a record needs the record"),
                              ("6000,0.5,,session.wav,3,1", "end_s", "line 2: must be after start_s (3 s), got 1 s"),
                              ("6000,0.5,,session.wav,-1,3", "start_s", "line 2: must be a finite number ≥ 0, got -1"),
                              ("6000,0.5,,session.wav,9,", "start_s",
                               "line 2: 9 s is after the end of its record session.wav (8 s)"),
                              ("6000,0.5,,session.wav,,x", "end_s", "line 2: 'x' is not a number")):
        p.write_text("rpm,depth_mm,result,record,start_s,end_s\n" + body + "\n")
        with pytest.raises(InputError) as exc:
            read_test_cuts(p, teeth=4)
        assert exc.value.field == field and said in exc.value.message, (body, exc.value)


EXAMPLE_SHOP = Path(__file__).resolve().parents[2] / "examples" / "shop"


def test_the_example_session_is_heard_as_the_true_tool_s_sdm_limit_says():
    """The README's session of test cuts (examples/shop/, written by examples/make_test_cuts.py): the prior file is
    the code's Cornelius case; the table read through its record gives each cut the verdict the virtual shop heard
    alone, and against the true tool's SDM limit (recomputed here from the true θ, not read) each cut's verdict is
    right outside ±5 % of the limit and the chatter frequency is the SDM's within 1 %."""
    from toolpoint.shop.model import sdm_limits

    prior = read_modal_prior(EXAMPLE_SHOP / "cornelius_prior.toml")
    assert prior == cornelius_2024(0.1)
    truth = json.loads((EXAMPLE_SHOP / "truth.json").read_text())
    cuts = read_test_cuts(EXAMPLE_SHOP / "test_cuts.csv", teeth=prior.cutting.teeth)
    assert len(cuts) == len(truth["cuts"]) >= 3 and {c.stable for c in cuts} == {True, False}
    for c, t in zip(cuts, truth["cuts"]):
        # each speed on its own, as the generator asks: the SDM's search found 0.5782 mm at 20276 rpm with three
        # speeds in one call and 0.5798 mm with that speed alone (2026-11-29), more than the 4 digits truth.json keeps
        (lim,), (fc,) = sdm_limits(prior, np.array(truth["theta"]), np.array([c.rpm]))
        assert ("stable" if c.stable else "chatter") == t["heard_alone"] and c.warnings == ()
        assert t["sdm_limit_mm"] == pytest.approx(1e3 * lim, rel=1e-3)
        ratio = c.depth_m / lim
        if abs(ratio - 1) > 0.05:
            assert c.stable == (ratio < 1), (c, ratio)
        if not c.stable:
            assert c.chatter_hz == pytest.approx(fc, rel=0.01)



@pytest.mark.slow  # 7–9 s: the fast tier read 177 s on the shared VM (limit 3 min)
def test_a_prior_from_a_measured_frf_holds_its_modes(tmp_path, capsys):
    """A shop's usual start: a tap test. The prior from its FRF (the trusted band, a driving point's modal fit) holds
    the virtual tap's three dominant modes — against the modes the records were made from, not against the fit — and
    its median lobes are the zero-order lobes of the measured FRF itself (a second method: no modal model) where
    they matter; the fit's own scatter over seeds is what MEASURED_SIGMA_STIFFNESS says it is (under 2 %)."""
    from toolpoint.frf import FRF
    from toolpoint.io.impact import Record, impact_frf
    from toolpoint.io.virtual_tap import LAB_MODES, close_xy_modes, lab_like_tap
    from toolpoint.shop.prior import MEASURED_SIGMA_STIFFNESS, prior_from_frf
    from toolpoint.stability import CuttingConditions
    from toolpoint.stability.measured import lobes_from_frf

    cut = CuttingConditions(4, 796e6, 0.212, 0.5)
    truth = close_xy_modes(LAB_MODES)[0:6:2]  # the x modes as the measurement direction sees them: k / cos²φ
    ks = []
    for seed in range(4):
        rec = lab_like_tap(seed=seed, hits=3, spacing_s=0.07)
        frf = impact_frf(Record(rec.time_s, rec.force_n, rec.acceleration_ms2, source="virtual")).frf
        with warnings.catch_warnings():  # extra poles of negative modal mass, on some seeds: said, and left out
            warnings.simplefilter("ignore")
            pr = prior_from_frf(frf, cut, source="tap.csv")
        assert len(pr.freq_hz) == 3
        for fn, k, z, m in zip(pr.freq_hz, pr.stiffness_n_m, pr.damping, truth):
            assert fn == pytest.approx(m.fn_hz, rel=0.002) and z == pytest.approx(m.zeta, rel=0.05)
            assert k == pytest.approx(m.stiffness_n_per_m, rel=0.05)
        ks.append(np.log(pr.stiffness_n_m))
        assert pr.sigma_stiffness == (MEASURED_SIGMA_STIFFNESS,) * 3 and pr.sigma_freq == (0.01,) * 3
    assert np.std(ks, axis=0, ddof=1).max() < 0.02
    # the prior's median lobes against the measured FRF's own zero-order lobes
    rpm = np.linspace(4000, 20000, 200)
    direct = lobes_from_frf(frf, cut, rpm).lobes.depth_m
    f = pr.freq_grid()
    median = zoa_limits(f, receptance(pr, pr.theta(np.zeros((1, pr.sigma.size))), f), cut, rpm)[0]
    ok = direct < 2 * np.median(direct)  # where the lobes matter (not the pockets' tips)
    assert np.median(np.abs(np.log(median[ok] / direct[ok]))) < 0.05 and ok.mean() > 0.7
    # the command line: --prior's [cut] and σ, --frf the tap test's FRF; a TOML naming its own FRF; bad input
    path = tmp_path / "tap.csv"
    from toolpoint.io.frf_files import write_frf

    write_frf(path, frf)
    toml = tmp_path / "tapped.toml"
    body = ('name = "tapped"\n[cut]\nteeth = 4\ntangential_coeff_n_mm2 = 796\nradial_ratio = 0.212\n'
            'radial_immersion = 0.5\n')
    toml.write_text(body)
    assert main([*UPDATE_ZOA, "--prior", str(toml), "--frf", str(path), "--samples", "200", "--out",
                 str(tmp_path / "u")]) == 0
    said = capsys.readouterr()
    assert said.out.startswith("prior tapped (modes of tap.csv, 86–7929 Hz): 1071.")
    assert "0 test cuts; recommended" in said.out
    # an accelerance in a CSV (tap --output-quantity measured: the file does not say it) is refused for its size,
    # and read as what the [measured] table says it is
    acc = tmp_path / "acc.csv"
    write_frf(acc, impact_frf(Record(rec.time_s, rec.force_n, rec.acceleration_ms2, source="virtual"),
                              output="measured").frf, as_measured=True)
    toml.write_text('[measured]\nfrf = "acc.csv"\n' + body)
    with pytest.raises(InputError, match=r"acc\.csv: measured\.frf: the largest \|H\| is .* m/N, orders of magnitude "
                                         r"from a tool point's .*quantity = \"accelerance\""):
        read_modal_prior(toml)
    toml.write_text('[measured]\nfrf = "acc.csv"\nquantity = "accelerance"\n' + body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.allclose(read_modal_prior(toml).freq_hz, pr.freq_hz, rtol=1e-6)
    toml.write_text('[measured]\nfrf = "tap.csv"\nsigma_stiffness = 0.2\n' + body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fit's note on extra poles (the command line prints it)
        assert read_modal_prior(toml).sigma_stiffness == (0.2,) * 3
    for text, field in (("[measured]\nsigma_freq = 0.01\n" + body, "measured.frf"),
                        ('[measured]\nfrf = "tap.csv"\nsigma_damping = 3\n' + body, "measured.sigma_damping"),
                        ('[measured]\nfrf = "tap.csv"\nmax_modes = 0\n' + body, "measured.max_modes"),
                        ('[measured]\nfrf = "tap.csv"\nband_hz = [3000, 300]\n' + body, "measured.band_hz"),
                        ('[measured]\nfrf = "none.csv"\n' + body, None),
                        ('[measured]\nfrf = "tap.csv"\n[[mode]]\nfreq_hz = 900\nstiffness_n_m = 1e7\n'
                         'damping = 0.03\n' + body, "mode"),
                        ('[measured]\nfrf = "tap.csv"\nband_hz = [5000, 6000]\n' + body, "measured.frf")):
        toml.write_text(text)
        with pytest.raises(InputError) as exc:
            read_modal_prior(toml)
        assert (exc.value.field == field if field else "none.csv" in str(exc.value)), (text, exc.value)
    toml.write_text(body)
    assert main([*UPDATE_ZOA, "--library", str(tmp_path), "--tool", "x", "--frf", str(path), "--out",
                 str(tmp_path / "v")]) == 2
    assert "--frf: only with --prior" in capsys.readouterr().err
    # a band that leaves out a dominant mode (a soft tip's, or one given too narrow): the fit's residual pole says
    # so, and the prior is refused rather than made without it (cut at 1500 Hz: the 1981 Hz mode; at 1100: 1071 Hz)
    for band, near in (((300.0, 1500.0), "near 20"), ((1100.0, 3000.0), "near 107")):
        with warnings.catch_warnings(), pytest.raises(InputError, match=f"a mode just outside the band .*{near}"):
            warnings.simplefilter("ignore")
            prior_from_frf(frf, cut, band=band, source="tap.csv")
    # … and a rubber tip's own band (up to 786 Hz), which ends below the dominant mode
    soft = lab_like_tap(seed=1, hits=3, spacing_s=0.07, tip="rubber")
    soft_frf = impact_frf(Record(soft.time_s, soft.force_n, soft.acceleration_ms2, source="virtual")).frf
    with warnings.catch_warnings(), pytest.raises(InputError, match="a mode just outside the band 71–786 Hz, near 10"):
        warnings.simplefilter("ignore")
        prior_from_frf(soft_frf, cut, source="rubber.csv")
    # an accelerometer mounted the wrong way round (the FRF's sign flipped): every mode of negative mass, refused
    with warnings.catch_warnings(), pytest.raises(InputError, match="no mode of positive modal mass"):
        warnings.simplefilter("ignore")
        prior_from_frf(FRF(frf.freq_hz, -frf.values), cut, source="reversed.csv")
    # real measured accelerances (pyuff's samples, 1 Hz lines, a lightly damped structure, not a tool point): the
    # driving point's dominant mode (51.5 Hz, ζ 0.03 %) falls between the lines, the transfer FRF is 20 × softer than
    # any tool point — both refused, saying what would decide, where a prior "51.5 Hz, ζ 0.03 % ± 20 %" would have
    # claimed what the data do not hold
    data = Path(__file__).resolve().parents[1] / "data" / "pyuff"
    for k, said in ((1, "the mode at 51.5 Hz (ζ 0.0317 %) is narrower than the FRF's line spacing"),
                    (2, "the largest |H| is 0.0022 m/N, orders of magnitude from a tool point's")):
        a = np.genfromtxt(data / f"meas_point_{k}.txt", dtype=complex)
        with warnings.catch_warnings(), pytest.raises(InputError) as exc:
            warnings.simplefilter("ignore")
            prior_from_frf(FRF(np.arange(1.0, a.size), a[1:], "accelerance"), cut, source=f"meas_point_{k}.txt")
        assert exc.value.field == "measured.frf" and said in exc.value.message, exc.value

def test_a_band_above_the_samples_own_sdm_limit_is_noted():
    """The band's 5 % limit at the recommended speed more than 5 % above the posterior samples' own SDM 5 % limit (a
    pocket's peak: 26 % of prior truths below the band's line on the README's tap prior, 4 % below the depth) is said;
    within 5 %, or without the check, nothing."""
    from toolpoint.shop.report import pocket_note

    said = pocket_note({"rpm": 13165.8, "limit_p05_mm": 6.4346, "own_sdm_p05_mm": 4.337})
    assert said.startswith("at 13166 rpm the band's 5 % limit (6.435 mm) lies 48 % above the held-out posterior "
                           "samples' own SDM 5 % limit (4.337 mm): the band is optimistic")
    # the band's samples weighted by their own SDM limits at the cut speeds (a draft of the example session): the gap is
    # the held-out samples' (weighted only by the cuts at its speed), and the line says so rather than blaming the
    # references
    said = pocket_note({"rpm": 20477.4, "limit_p05_mm": 0.5598, "own_sdm_p05_mm": 0.5268, "lobes_own_sdm": True})
    assert said.startswith("at 20477 rpm the band's 5 % limit (0.560 mm) lies 6 % above") and \
        "the held-out ones only by the cuts at this speed" in said and "optimistic" not in said
    assert pocket_note({"rpm": 9000.0, "limit_p05_mm": 1.04, "own_sdm_p05_mm": 1.0}) is None
    assert pocket_note({"rpm": 9000.0, "limit_p05_mm": 1.5, "own_sdm_p05_mm": None}) is None

def test_the_update_plot_shows_the_cuts_near_the_recommendation():
    """lobes.png's right panel holds every cut, the recommended point and the next cut inside its limits (over the
    whole speed range they sat on each other: the README's figure), with the band there."""
    from toolpoint.shop.report import plot_update

    prior = read_modal_prior(EXAMPLE_SHOP / "cornelius_prior.toml")
    cuts = [TestCut(20176.0, 0.504e-3, True), TestCut(20276.0, 0.542e-3, True), TestCut(20276.0, 0.599e-3, False,
                                                                                         1850.8)]
    post = update(prior, cuts, rng=np.random.default_rng(0), forward="zoa", n_samples=200, lobe_samples=100)
    full, near = plot_update(post).axes[:2]
    (x0, x1), (y0, y1) = near.get_xlim(), near.get_ylim()
    pts = [(c.rpm, 1e3 * c.depth_m) for c in cuts] + [(d["rpm"], 1e3 * d["depth_m"]) for d in (post.next_cut,
                                                                                               post.recommended)]
    assert all(x0 < x < x1 and y0 < y < y1 for x, y in pts), (pts, near.get_xlim(), near.get_ylim())
    assert x1 - x0 < 0.2 * (full.get_xlim()[1] - full.get_xlim()[0])  # a zoom, not the range again
    j = (post.rpm > x0) & (post.rpm < x1)
    assert y1 >= 1e3 * post.limit_q_m[2][j].max()  # the band's top is in view
    labels = near.get_legend_handles_labels()[1]
    assert "stable cut" in labels and "chatter cut" in labels

@pytest.mark.slow
def test_the_example_session_is_the_cuts_update_proposed(tmp_path, capsys):
    """examples/shop/test_cuts.csv is what examples/make_test_cuts.py writes, and each of its cuts is the next cut
    `toolpoint update` proposes from the rows before it (the README's tour says so)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_test_cuts", EXAMPLE_SHOP.parent / "make_test_cuts.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    gen.main(tmp_path)
    capsys.readouterr()
    assert (tmp_path / "test_cuts.csv").read_text() == (EXAMPLE_SHOP / "test_cuts.csv").read_text()
    assert json.loads((tmp_path / "truth.json").read_text())["cuts"] == json.loads(
        (EXAMPLE_SHOP / "truth.json").read_text())["cuts"]
    rows = (EXAMPLE_SHOP / "test_cuts.csv").read_text().splitlines()
    for n in range(len(rows) - 1):
        table = tmp_path / f"first{n}.csv"
        table.write_text("\n".join(rows[:n + 1]) + "\n")
        args = ["update", "--prior", str(EXAMPLE_SHOP / "cornelius_prior.toml"), "--out", str(tmp_path / f"u{n}")]
        assert main(args + (["--cuts", str(table)] if n else [])) == 0
        doc = json.loads((tmp_path / f"u{n}" / "update.json").read_text())
        nc = doc["next_cut"]
        assert doc["sampler"]["forward"] == "sdm"  # the default: what the README's tour and the campaigns use
        rpm, depth = (float(v) for v in rows[n + 1].split(",")[:2])
        # the table holds the proposal to 1 rpm and 0.001 mm, update.json to 0.0001 mm (0.5695 → 0.569 in the table)
        assert round(nc["rpm"]) == rpm and abs(nc["depth_mm"] - depth) <= 0.00055, (n, nc)


def _prior_updates(seed0, seeds, n_speeds, truths=150):
    """Prior-only updates of the example tool (σ 0.15, ``forward="sdm"``, 500 samples, 200 lobe samples), each with
    truths drawn from the prior after it: yields (posterior, truth_limits), truth_limits(rpm) the truths' SDM limits
    at one speed by the full upward search (not the update's)."""
    from toolpoint.shop.model import example_tool, sdm_limits

    pr = example_tool(0.15)
    for seed in range(seeds):
        rng = np.random.default_rng(seed0 + seed)
        post = update(pr, [], rng=rng, n_samples=500, lobe_samples=200, forward="sdm",
                      rpm_grid=np.linspace(5000.0, 30000.0, n_speeds))
        th = pr.theta(rng.standard_normal((truths, pr.sigma.size)) * (pr.sigma > 0))
        yield post, lambda rpm, th=th: np.array([sdm_limits(pr, t, np.array([rpm]), chatter=False)[0][0] for t in th])


@pytest.mark.slow
def test_the_first_cut_s_risk_holds_on_truths_from_the_prior():
    """Out of sample: truths drawn from the example tool's prior (3 lightly damped modes, σ 0.15) whose SDM limit
    (the full upward search, not the update's) lies below the first proposed cut chatter at about the claimed rate.
    With the four references' ratio alone the first cuts claimed 0.28 and 0.37 of such truths chattered (8 seeds,
    100 truths each); with the samples' own SDM limits at the cut's speed 0.30 claimed, 0.28 realised. This test
    (60 speeds instead of 200, which costs a third less; 2026-11-27): 0.29 claimed, 0.39 realised without that
    check; 0.30 and 0.29 with it. 35 s alone (45 s before one BLAS controller per process)."""
    claimed, realised = [], []
    for post, truth_limits in _prior_updates(1000, 3, 60):
        nc = post.next_cut
        assert nc["p_chatter"] <= 0.3 + 1e-9
        a = truth_limits(nc["rpm"])
        claimed.append(nc["p_chatter"])
        realised.append(np.mean(a < nc["depth_m"]))
    # 450 truths: the realised share's standard error is ~0.02; the bias was +0.09
    assert np.mean(realised) <= np.mean(claimed) + 0.05, (claimed, realised)
    assert np.mean(realised) >= np.mean(claimed) - 0.1, (claimed, realised)  # not bought by cutting far too shallow


@pytest.mark.slow
def test_the_recommended_depth_holds_on_truths_from_the_prior():
    """Out of sample: truths drawn from the example tool's prior whose SDM limit (the full upward search) lies below
    the prior's recommended depth, at its speed — it claims P(stable) 0.95. The band's 5 % limit there is not
    calibrated: the speed is chosen where the lobe samples' and the four references' estimate looks most
    productive (8 seeds × 100 truths on 200 speeds: 0.138 of the truths below it); the depth checked by the own SDM
    limits of posterior samples that are not the lobe samples, 0.046 (``docs/design/shop.md``). Here (4 seeds × 150
    truths, 100 speeds; 2026-11-27): 0.113 below the band's 5 % limit, 0.057 below the checked depth."""
    band, checked = [], []
    for post, truth_limits in _prior_updates(2000, 4, 100):
        rc = post.recommended
        assert rc["depth_m"] <= rc["limit_p05_m"] and rc["p_stable"] >= 0.95
        a = truth_limits(rc["rpm"])
        band.append(np.mean(a < rc["limit_p05_m"]))
        checked.append(np.mean(a < rc["depth_m"]))
    # 600 truths: the realised share's standard error is ~0.01 at 0.05
    assert np.mean(checked) <= 0.05 + 0.03, (band, checked)
    assert np.mean(checked) >= 0.01, (band, checked)  # not bought by recommending far too shallow


def test_a_lower_risk_after_the_first_chatter():
    # risk_after_chatter bounds the next cut's P(chatter) only once a cut has chattered: with stable cuts alone the
    # proposal is the default's (same draws); after a chatter it is shallower, within the lower bound (or a step
    # above stable cuts that crept, which the option leaves alone), and the proposal says which bound it used.
    pr = cornelius_2024(0.1)
    kw = dict(n_samples=300, lobe_samples=150, label_offset=(0, 0), label_growth=(0, 0), forward="zoa")
    stable = [TestCut(20000.0, 0.45e-3, True)]
    a = update(pr, stable, rng=np.random.default_rng(4), **kw).next_cut
    b = update(pr, stable, rng=np.random.default_rng(4), risk_after_chatter=0.1, **kw).next_cut
    _assert_same_cut(a, b)
    assert a["risk"] == 0.3
    cuts = stable + [TestCut(20000.0, 0.8e-3, False, 1290.0)]
    a = update(pr, cuts, rng=np.random.default_rng(4), **kw).next_cut
    b = update(pr, cuts, rng=np.random.default_rng(4), risk_after_chatter=0.1, **kw).next_cut
    assert a["risk"] == 0.3 and b["risk"] == 0.1 and "≤ 0.1" in b["description"]
    assert b["p_chatter"] <= 0.1 + 1e-9 or b["stepped"], b
    assert a["p_chatter"] > 0.1 and b["depth_m"] < a["depth_m"] or a["rpm"] != b["rpm"], (a, b)
    r = update(pr, cuts, rng=np.random.default_rng(4), rule="risk", risk=0.2, risk_after_chatter=0.05, **kw).next_cut
    assert r["risk"] == 0.05 and r["p_chatter"] <= 0.05 + 1e-9
    with pytest.raises(InputError, match="risk_after_chatter"):
        update(pr, cuts, rng=np.random.default_rng(4), risk_after_chatter=0.4, **kw)


def test_a_doubtful_record_s_warning_reaches_update_s_report(tmp_path, capsys):
    # A record without an air cut whose "chatter" sits on 50 Hz (hum from a ground loop: `cut` cannot tell the two
    # apart, test_cut.py) keeps its chatter label, and its warning goes with the cut to update.json, report.html and
    # one stderr line naming the table, the line and the record. A record without a doubt carries none.
    import soundfile as sf

    from shop_synth import shop_record

    x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=0.0, fans=(), seed=0)
    t = np.arange(x.size) / rate
    a = np.std(x) * 10 ** (-10 / 20)
    x = x + sum(a / k * np.sin(2 * np.pi * 50 * k * t + k) for k in (1, 3, 5, 7))
    sf.write(tmp_path / "hum.wav", 0.5 * x / np.abs(x).max(), int(rate), subtype="PCM_16")
    y, rate, *_ = shop_record(rpm=12000, teeth=4, chatter_hz=1310.0, chatter_amp=0.5, seed=8)
    sf.write(tmp_path / "c1.wav", y, int(rate), subtype="PCM_16")
    (tmp_path / "prior.toml").write_text(PRIOR_TOML)
    cuts = tmp_path / "cuts.csv"
    cuts.write_text("rpm,depth_mm,result,record\n6000,2.0,,hum.wav\n12000,0.8,,c1.wav\n20000,0.5,stable,\n")
    read = read_test_cuts(cuts, teeth=4)
    assert [c.stable for c in read] == [False, False, True] and abs(read[0].chatter_hz - 50) < 0.5
    assert len(read[0].warnings) == 1 and read[0].warnings[0].startswith("hum.wav: chatter at 50.0 Hz sits on")
    assert read[1].warnings == () and read[2].warnings == ()
    out = tmp_path / "out"
    assert main([*UPDATE_ZOA, "--prior", str(tmp_path / "prior.toml"), "--cuts", str(cuts), "--out", str(out),
                 "--samples", "200"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith(f"{cuts}: line 2: warning: hum.wav: chatter at 50.0 Hz"), err
    # and, the update's own check, that 50 Hz lies far from the prior's modes (1243, 1747 Hz): the same line
    assert len(err) == 2 and err[1].startswith(f"{cuts}: line 2: warning: chatter at 50.0 Hz"), err
    assert "far from every mode" in err[1], err
    doc = json.loads((out / "update.json").read_text())
    assert [len(c["warnings"]) for c in doc["cuts"]] == [1, 0, 0]
    assert doc["cuts"][0]["warnings"][0].startswith("line 2: hum.wav: chatter at 50.0 Hz")
    html = (out / "report.html").read_text()
    assert "Warnings from the records" in html and "line 2: hum.wav: chatter at 50.0 Hz sits on the mains" in html


@pytest.mark.slow
@pytest.mark.first
def test_virtual_campaigns_on_the_example_tool_meet_the_targets():
    """The loop on the example tool (3 lightly damped modes, σ 0.15), its own forward model, seeds 0–4 with the
    settings of ``benchmarks/bench_shop.py`` and δ = 0 (the shop's labels are the limit):
    median cuts to converge ≤ 6 and median chattering cuts ≤ 1 (issue
    25's targets). Measured on these seeds (2026-11-25): cuts 6, 5, 4, not within 8, 4 (median 5: margin one cut);
    chattering cuts 1, 1, 1, 6, 1 (median 1: no margin); 4/5 converged (no margin). Seed 3 is a truth in the prior's
    tail (K_t 3.3 σ above its median). ~2.5 min CPU."""
    from toolpoint.shop.model import example_tool

    pr = example_tool(0.15)
    cuts, chat = [], []
    for seed in range(5):
        # the zero-order shop labels by the limit itself: δ = 0 and G = 0 known
        r = virtual_campaign(pr, rng=np.random.default_rng(seed), forward="zoa", max_cuts=8, n_samples=500,
                             lobe_samples=200, label_offset=(0, 0), label_growth=(0, 0))
        cuts.append(np.inf if r.converged_after is None else r.converged_after)
        made = r.cuts if r.converged_after is None else r.cuts[:r.converged_after]
        chat.append(sum(not c.stable for c in made))
    assert np.median(cuts) <= 6, cuts
    assert np.median(chat) <= 1, chat
    assert sum(np.isfinite(cuts)) >= 4, cuts


@pytest.mark.slow
@pytest.mark.first
def test_the_corrected_samples_own_sdm_limits_move_the_band_to_the_sdm():
    """A wide prior (σ 0.05): the references' SDM/ZOA ratio is that of the zero-order posterior, which moved its
    parameters to explain cuts that follow the SDM. Six truths drawn from the prior, cuts bracketing each one's
    SDM limit (±7 %) at 7000 and 7500 rpm (flip lobes, ZOA ~35 % low): with ``sdm_train=60`` (the corrected
    samples' own SDM limits at the cut speeds) the band holds the SDM limit at both speeds for every truth, and the
    median is closer to it than with the references alone. The labels are the SDM limit's own, so the label model is
    off (offset and growth 0). Measured (2026-12-07): mean |ln(median / SDM)| 0.029 against 0.032. Until then the
    test ran ``update``'s default label model, whose offset prior N(0.035, 0.035²) put the references' median low:
    0.032 against 0.050 on that day's code; with the offset refitted to ``cut`` (N(0.01, 0.02²)) 0.029 against 0.024,
    a comparison these exact labels do not ask for."""
    from toolpoint.stability import sdm_lobes

    pr = cornelius_2024(0.05)
    rpm = np.array([7000.0, 7500.0])
    err = {0: [], 60: []}
    for seed in range(6):
        th = pr.theta((np.random.default_rng(100 + seed).standard_normal(pr.sigma.size) * (pr.sigma > 0))[None])[0]
        mm, cut = pr.tool(th)
        a_sdm = sdm_lobes(mm, mm, cut, rpm=rpm).depth_m
        cuts = [TestCut(float(r), float(a * q), bool(q < 1)) for r, a in zip(rpm, a_sdm) for q in (0.93, 1.07)]
        for tr in err:
            q = update(pr, cuts, rng=np.random.default_rng(0), n_samples=300, lobe_samples=150, forward="sdm",
                       sdm_refs=2, rpm_grid=rpm, sdm_train=tr, sdm_train_model="mean", own_sdm=False,
                       label_offset=(0, 0), label_growth=(0, 0)).limit_q_m / a_sdm
            err[tr].extend(np.abs(np.log(q[1])))
            if tr:
                assert np.all(q[0] <= 1) and np.all(1 <= q[2]), (seed, q)
    assert np.mean(err[60]) < 0.035 and np.mean(err[60]) < np.mean(err[0]), {k: np.mean(v) for k, v in err.items()}


def test_the_ratio_fit_recovers_a_quadratic_and_holds_its_range():
    """``sdm_train_model="quadratic"``: each sample's SDM/ZOA ratio at the cut speeds from its prior coordinates. On
    ratios that are exactly quadratic in the free columns of z the fit recovers them on fresh samples to rounding
    (a fixed column is ignored, the search's failures — ratio 0 — are left out), its residual sd is the noise's
    added to them (χ² with T − p degrees of freedom), a sample far outside the training cloud is held within the
    training range widened by one residual sd, a speed with too few rows gets their mean, and ``_at`` hands the
    likelihood each sample's ratio per cut."""
    from toolpoint.shop.update import _at, _RatioFit

    rng = np.random.default_rng(7)
    free = np.array([True, True, False, True])
    T = 200

    def truth(z):  # two speeds, each quadratic in the free columns
        return np.c_[0.3 + 0.05 * z[:, 0] - 0.02 * z[:, 1] + 0.01 * z[:, 3] ** 2,
                     0.1 - 0.03 * z[:, 3] + 0.02 * z[:, 0] ** 2]

    z = rng.standard_normal((T, 6)) * np.r_[free, True, True]
    lr = truth(z)
    lr[:7, 1] = 0.0  # the search found no limit there
    inv = np.array([0, 1, 1])  # three cuts, two at the second speed
    fit = _RatioFit(z, lr, free, inv)
    znew = rng.standard_normal((50, 6)) * np.r_[free, True, True]
    kept = [lr[:, k][lr[:, k] != 0] for k in range(2)]  # the range (no noise: no widening) of the training ratios
    held = np.clip(truth(znew), [v.min() for v in kept], [v.max() for v in kept])
    assert np.mean(held == truth(znew)) > 0.9  # most fresh samples inside it
    np.testing.assert_allclose(fit(znew), held[:, inv], atol=1e-12)
    assert np.all(fit.resid_sd < 1e-12)
    # noise: the residual sd estimates it (sd of the estimate ≈ σ / √(2 (T − p)): 5 % here)
    noisy = truth(z) + rng.normal(0, 0.02, (T, 2))
    fit_n = _RatioFit(z, noisy, free, inv)
    np.testing.assert_allclose(fit_n.resid_sd, 0.02, rtol=0.2)
    # far outside the training cloud: held within [min − sd, max + sd] of the training ratios
    far = np.zeros((1, 6))
    far[0, 0] = 40.0
    out = fit_n(far)[0]
    assert np.all(out <= noisy.max(axis=0)[inv] + fit_n.resid_sd[inv] + 1e-12)
    assert out[0] == pytest.approx(noisy[:, 0].max() + fit_n.resid_sd[0])
    # too few rows for the 7 coefficients (fewer than 14): their mean, their sd
    few = _RatioFit(z[:10], noisy[:10], free, inv)
    np.testing.assert_allclose(few(znew), np.broadcast_to(noisy[:10].mean(axis=0)[inv], (50, 3)), atol=1e-12)
    np.testing.assert_allclose(few.resid_sd, noisy[:10].std(axis=0, ddof=1))
    kw = _at(dict(boundary_width=0.05, ratio_fit=fit), znew)
    assert "ratio_fit" not in kw and kw["log_ratio"].shape == (50, 3)
    assert _at(dict(boundary_width=0.05), znew) == dict(boundary_width=0.05)


def test_per_speed_quantiles_are_numpys():
    """The band's quantiles at per-speed levels equal numpy's at the same level, nan and inf columns included."""
    rng = np.random.default_rng(5)
    x = rng.lognormal(size=(400, 6))
    x[:, 2] = np.inf  # no lobe reaches the speed
    x[:5, 3] = np.inf
    x[3, 4] = np.nan
    for lv in ([0.05, 0.5, 0.95], [0.0, 1.0, 0.013]):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            want = np.quantile(x, lv, axis=0)
            got = _quantiles_at(x, np.array(lv)[:, None] * np.ones((1, 6)))
        np.testing.assert_allclose(got, want, equal_nan=True)


@pytest.mark.slow  # 4.5–6.5 s each, a calibration over 1500 draws: the fast tier read 181 s on a clean clone (3 min)
@pytest.mark.parametrize("tau, plain_lo, plain_hi", [(0.0, 0.045, 0.058), (0.1, 0.055, 0.068)])
def test_the_band_allows_for_its_few_references(tau, plain_lo, plain_hi):
    """Lobes built as ``update`` builds them away from the cut speeds — each sample's zero-order limit (ln sd 0.2)
    times one of four references' ratios (offsets ln sd ``tau``) — and a truth drawn from the population (ln sd
    √(0.2² + tau²)): the widened 5 % and 95 % lines miss it 0.05 of the time each (3 × 1500 draws: ± 0.01), where the
    plain ones miss it more often once the references spread; with identical references the levels stay ~5 %.
    The P(stable) map claims what the band does: 0.95 on its 5 % line (within a sample's step), and the probability it
    gives the truth's own limit of chatter is uniform (a calibrated map; the lobe samples' plain share is not, once
    the references spread)."""
    rng = np.random.default_rng(7)
    n, m, R, G = 1500, 400, 4, 3
    miss = np.zeros(2)
    plain = np.zeros(2)
    levels, pit, pit0 = [], [], []
    for _ in range(n):
        offs = rng.normal(0.0, tau, (R, G))
        rows = rng.integers(R, size=m)
        lim = np.exp(rng.normal(0.0, 0.2, (m, G)) + offs[rows])
        truth = np.exp(rng.normal(0.0, math.hypot(0.2, tau), G))
        lv = _band_levels(lim, rows, R, np.arange(m), rng)
        q = _quantiles_at(lim, lv)
        q0 = np.quantile(lim, [0.05, 0.95], axis=0)
        miss += [np.sum(truth < q[0]), np.sum(truth > q[1])]
        plain += [np.sum(truth < q0[0]), np.sum(truth > q0[1])]
        levels.append(lv[0])
        # on the lines within a sample's step of the share (1/400, magnified up to ~3× where the levels are low)
        np.testing.assert_allclose(_p_chatter_map(lim, q, lv), [[0.05] * G, [0.95] * G], atol=0.01)
        pit.append(_p_chatter_map(lim, truth[None, :], lv)[0])
        pit0.append(1.0 - (lim > truth).mean(axis=0))
    miss /= n * G
    plain /= n * G
    assert np.all(np.abs(miss - 0.05) <= 0.01), miss
    pit, pit0 = np.ravel(pit), np.ravel(pit0)
    for x, tol in ((0.05, 0.01), (0.25, 0.015), (0.5, 0.015), (0.75, 0.015), (0.95, 0.01)):
        assert abs(np.mean(pit <= x) - x) <= tol, (x, np.mean(pit <= x))
    if tau > 0:  # the plain share claims too much at both ends
        lo, hi = np.mean(pit0 <= 0.05), np.mean(pit0 <= 0.95)
        assert lo > 0.055 and hi < 0.945, (lo, hi)
    assert plain_lo <= plain.mean() <= plain_hi, plain
    if tau == 0:
        assert abs(np.median(levels) - 0.05) < 0.003
    else:
        assert np.median(levels) < 0.047 and plain.mean() - miss.mean() > 0.005


def test_the_p_stable_map_runs_on_beyond_the_samples():
    """Under the lowest lobe sample the samples' share says P(chatter) 0; where the band's lines were widened far
    (level 0.001) the band's own normal model does not: the map goes on from the lowest sample and falls to 0 only as
    the depth does, monotonically, and so above the highest. At plain levels it is the share among the samples."""
    rng = np.random.default_rng(2)
    lim = np.exp(rng.normal(0.0, 0.2, (400, 1)))
    lo, hi = lim.min(), lim.max()
    wide = np.array([[0.001], [0.999]])
    d = np.r_[1e-9, np.geomspace(0.2 * lo, 0.999 * lo, 30), np.geomspace(1.001 * lo, 0.999 * hi, 50),
              np.geomspace(1.001 * hi, 5 * hi, 30), 1e9]
    pc = _p_chatter_map(lim, d, wide)[:, 0]
    assert np.all(np.diff(pc) >= 0) and pc[0] < 1e-9 and pc[-1] > 1 - 1e-9
    assert pc[30] > 0.02 and pc[81] < 0.98, (pc[30], pc[81])  # just under the lowest (over the highest) sample
    plain = _p_chatter_map(lim, d[31:81], np.array([[0.05], [0.95]]))[:, 0]
    np.testing.assert_allclose(plain, 1.0 - (lim[:, 0] > d[31:81, None]).mean(axis=1), atol=1e-12)
    assert _p_chatter_map(lim, d[:31], np.array([[0.05], [0.95]]))[:, 0].max() < 0.002  # ~1/(2 × 400) at most


def test_the_posterior_reads_its_map_at_any_depth():
    """``Posterior.p_chatter`` is the P(stable) map read at any depth: 1 − ``p_stable`` on the map's own depths, the
    band's quantile levels on its lines, per-speed depths read at their own speed, and a scalar at every speed."""
    pr = cornelius_2024(0.1)
    cuts = [TestCut(18000.0, 0.4e-3, True), TestCut(18000.0, 0.6e-3, False, 1300.0)]
    post = update(pr, cuts, rng=np.random.default_rng(4), n_samples=300, lobe_samples=150, forward="zoa")
    np.testing.assert_allclose(post.p_chatter(np.repeat(post.depth_m[:, None], post.rpm.size, axis=1)),
                               1.0 - post.p_stable, atol=1e-12)
    lo, hi = post.p_chatter(post.limit_q_m[0]), post.p_chatter(post.limit_q_m[2])
    ok = np.isfinite(post.limit_q_m[0])
    lim = post.lobe_limit_m
    assert lim.shape == (150, post.rpm.size)
    # one reference (forward="zoa"): the levels are 0.05 / 0.95 and the map the samples' share itself — near the
    # lines within a few samples' step (1/150; resampled samples repeat)
    assert np.all(post.band_levels == np.array([[0.05], [0.95]]))
    np.testing.assert_allclose(lo[ok], (lim[:, ok] <= post.limit_q_m[0, ok]).mean(axis=0), atol=1e-12)
    assert np.all(np.abs(lo[ok] - 0.05) <= 0.015) and np.all(np.abs(hi[ok] - 0.95) <= 0.015)
    share = (lim <= 0.5e-3).mean(axis=0)  # among the samples the share; beyond them the band's normal model
    inner = ok & (share > 0) & (share < 1)
    assert inner.sum() > 20
    np.testing.assert_allclose(post.p_chatter(0.5e-3)[inner], share[inner], atol=1e-12)
    assert post.p_chatter(1e-9).max() < 1e-6 and post.p_chatter(1.0).min() > 1 - 1e-6
    assert np.all(np.isnan(post.p_chatter(np.nan)))  # a speed whose depth is unknown gets no claim


def test_own_sdm_weights_are_tempered_only_as_far_as_the_samples_need():
    """The own-SDM weights' power: 1 where the weights leave enough samples effective; else the largest power that
    keeps the ESS at the floor — computed here independently, as the ESS Σw² form on a fine grid of powers."""
    rng = np.random.default_rng(3)
    flat = rng.normal(0.0, 0.1, 400)  # nearly equal weights: ESS ≈ 400
    assert _own_temper(flat, 100.0) == 1.0
    for scale in (3.0, 8.0, 30.0):  # heavy weights: a handful of samples carry them
        lw = rng.normal(0.0, scale, 400)

        def ess(a):
            w = np.exp(a * (lw - lw.max()))
            return w.sum() ** 2 / (w ** 2).sum()

        assert ess(1.0) < 100
        alpha = _own_temper(lw, 100.0)
        grid = np.linspace(1e-4, 1.0, 20001)
        best = grid[np.array([ess(a) for a in grid]) >= 100].max()
        assert 0 < alpha < 1 and ess(alpha) >= 100 - 1e-6 and abs(alpha - best) < 1e-3, (scale, alpha, best)
    # weights of 0 (lw = −∞) on 350 of the 400: no power leaves 100 effective; the power stays positive and the
    # weights finite where they were
    lw = np.where(np.arange(400) < 50, rng.normal(0.0, 3.0, 400), -np.inf)
    alpha = _own_temper(lw, 100.0)
    w = np.exp(alpha * (lw - lw.max()))
    assert 0 < alpha < 1e-6 and np.all(np.isfinite(w)) and np.count_nonzero(w) == 50


def test_the_recommended_depths_check_weighs_held_out_samples_by_the_cuts_at_its_speed():
    """The held-out samples' own limits at the recommended speed are weighted by the cuts within 0.4 % of it: each
    sample's weight is the cuts' likelihood with its own limit there over the sampling's (closed form here: a chatter
    label's P = ε + (1 − 2ε) Φ((ln a − ln a_lim − δ) / w)); a cut at another speed cancels; no cut near: no weights.
    The weighted 5 % limit is then the deepest own limit with at most 5 % of the weight at or below it."""
    from scipy.stats import norm

    from toolpoint.shop.update import _own_limits, _own_weights_at, _recommended_own

    pr = cornelius_2024(0.1)
    P = pr.sigma.size
    f = pr.freq_grid()  # the frequency grid of the zero-order limits
    rng = np.random.default_rng(5)
    z = rng.standard_normal((120, P + 2))
    rpm = 9000.0
    a_zoa = limit_at_speeds(pr, pr.theta(z[:, :P]), [rpm], f)[0][:, 0]
    own = a_zoa * np.exp(rng.normal(0.2, 0.1, 120))  # the samples' own SDM limits, spread about the sampling's ratio
    a_c = float(np.median(own))
    cuts = [TestCut(rpm * 1.003, a_c, False), TestCut(7000.0, 1e-4, True)]
    eps, w, off_sd = 0.002, 0.05, 0.03
    kw = dict(boundary_width=np.array([0.08, 0.08]), label_noise=eps, freq_hz=f, log_ratio=np.array([-1.0, 0.0]),
              label_offset=(0.0, off_sd), label_growth=(0.0, 0.0), growth_error=None)
    wt = _own_weights_at(pr, z, f, rpm, own, cuts, kw, w)
    # by hand: the chatter cut's likelihood with the own limit (width w) over the sampling's (ratio e^−1, width
    # 0.08: there every sample's limit lies far under the cut, its likelihood ≈ 1, and the weight is the own
    # limit's alone), each sample with its own label offset; the own limit at 9000 rpm stands for the cut's speed
    # (0.3 % away)
    a_cut = limit_at_speeds(pr, pr.theta(z[:, :P]), [rpm * 1.003], f)[0][:, 0]
    delta = off_sd * z[:, P]

    def p_chatter(lim, width):
        return eps + (1 - 2 * eps) * norm.cdf((np.log(a_c) - np.log(lim) - delta) / width)

    ref = p_chatter(own, w) / p_chatter(a_cut * np.exp(-1.0), 0.08)
    assert np.allclose(wt, ref / ref.max(), rtol=1e-9, atol=1e-12)
    # half the samples put their own limit above the cut heard chattering (a_c their median); weighted, few
    assert np.sum(wt[own > a_c]) / wt.sum() < 0.2
    assert _own_weights_at(pr, z, f, 8500.0, own, cuts, kw, w) is None  # no cut within 0.4 %
    # the weighted 5 % limit against a weighted quantile computed here
    grid = np.array([8000.0, rpm, 10000.0])
    lim = np.tile(own[:, None], (1, 3))  # the lobes: the samples' own limits (the guess of the search)
    rec = {"rpm": rpm, "depth_m": 10.0, "p_stable": 1.0}
    got = _recommended_own(pr, z, f, grid, lim, rec, cuts=cuts, kw=kw, boundary_width=w)
    o = _own_limits(pr, z, f, grid, lim, 1, False)
    wo = _own_weights_at(pr, z, f, rpm, o, cuts, kw, w)
    order = np.argsort(o)
    cdf = np.cumsum(wo[order]) / wo.sum()
    q = o[order][cdf <= 0.05 + 1e-9].max()
    assert got["own_sdm_p05_m"] == pytest.approx(q, rel=1e-12) and got["depth_m"] == got["own_sdm_p05_m"]
    assert np.sum(wo[o <= q]) / wo.sum() <= 0.05 + 1e-9 < np.sum(wo[o <= o[order][np.searchsorted(o[order], q) + 1]]) \
        / wo.sum()
    assert got["p_stable"] == pytest.approx(np.sum(wo[o > q]) / wo.sum()) and got["p_stable"] >= 0.95
    assert got["own_sdm_p05_m"] != np.sort(o)[int(0.05 * o.size) - 1]  # not the unweighted 5 % limit


@pytest.mark.slow
def test_the_lobe_samples_weighted_by_their_own_sdm_limits_hold_the_sdm_limit():
    """As above (six truths, cuts ±7 % about each one's SDM limit at the flip lobes' 7000 and 7500 rpm), with
    ``own_sdm`` (the default) instead of ``sdm_train``: the band at the cut speeds is made of the lobe samples' own
    SDM limits — against an independent full search (:func:`sdm_lobes`) of ``lobe_z``'s, within 3 % (measured
    0.977–1.000 before the weights were tempered, 0.999–1.000 since: ``sdm_limit_near`` halves its bracket twice) —
    holds every truth's SDM limit at both speeds (without the weights truth 4's 7000 rpm limit lay below the band),
    and its median is closer to it (measured mean |ln(median / SDM)| 0.024 against 0.065 without the weights; on the
    code of 2026-12-01 evening 0.024 against 0.052, ESS 37.5–89.5 of 150, two of the six updates tempered to α 0.83
    and 0.91; ESS 20–84 before the tempering)."""
    from toolpoint.stability import sdm_lobes

    pr = cornelius_2024(0.05)
    rpm = np.array([7000.0, 7500.0])
    P = pr.sigma.size
    err = {True: [], False: []}
    for seed in range(6):
        th = pr.theta((np.random.default_rng(100 + seed).standard_normal(P) * (pr.sigma > 0))[None])[0]
        mm, cut = pr.tool(th)
        a_sdm = sdm_lobes(mm, mm, cut, rpm=rpm).depth_m
        cuts = [TestCut(float(r), float(a * q), bool(q < 1)) for r, a in zip(rpm, a_sdm) for q in (0.93, 1.07)]
        for own in err:
            post = update(pr, cuts, rng=np.random.default_rng(0), n_samples=300, lobe_samples=150, forward="sdm",
                          sdm_refs=2, rpm_grid=rpm, own_sdm=own)
            q = post.limit_q_m / a_sdm
            err[own].extend(np.abs(np.log(q[1])))
            if not own:
                assert post.own_sdm_ess is None
                continue
            assert np.all(q[0] <= 1) and np.all(1 <= q[2]), (seed, q)
            # tempered where the full weights leave fewer than a quarter of the samples effective
            assert OWN_MIN_ESS * 150 - 1e-6 <= post.own_sdm_ess <= 150 and post.lobe_z.shape == (150, P + 2)
            assert 0 < post.own_sdm_power <= 1
            if seed < 2:
                own_lim = np.array([sdm_lobes(*pr.tool(t)[:1] * 2, pr.tool(t)[1], rpm=rpm).depth_m
                                    for t in pr.theta(post.lobe_z[:, :P])])
                ratio = post.limit_q_m / np.quantile(own_lim, [0.05, 0.5, 0.95], axis=0)
                assert np.all(np.abs(ratio - 1) < 0.03), ratio
    assert np.mean(err[True]) < 0.035 and np.mean(err[True]) < np.mean(err[False]), \
        {k: np.mean(v) for k, v in err.items()}


@pytest.mark.slow
def test_sdm_forward_model_follows_cuts_that_follow_the_sdm():
    """A narrow prior (σ 0.02: the posterior stays near the SDM references) and cuts labelled by the SDM limit of
    its median tool at speeds where the ZOA is ~35 % too low (flip lobes, 50 % immersion): the ``forward="sdm"``
    posterior's band holds the SDM limit and its median is within 10 %; the zero-order posterior's is not.
    (With a wide prior the zero-order posterior moves its parameters to explain such cuts and the references'
    ratio no longer fits the corrected posterior: docs/design/shop.md.)"""
    from toolpoint.stability import ModalModel, sdm_lobes

    pr = cornelius_2024(0.02)
    th = pr.theta(np.zeros((1, pr.sigma.size)))[0]
    mm = ModalModel(th[:2], th[4:6], th[2:4] / (2 * np.pi * th[:2]) ** 2)
    rpm = np.array([7000.0, 7500.0])
    a_sdm = sdm_lobes(mm, mm, pr.cutting, rpm=rpm).depth_m
    cuts = [TestCut(float(r), float(a * q), bool(q < 1)) for r, a in zip(rpm, a_sdm) for q in (0.93, 1.07)]
    med = {}
    for fw in ("zoa", "sdm"):
        post = update(pr, cuts, rng=np.random.default_rng(0), n_samples=300, lobe_samples=150, forward=fw,
                      sdm_refs=2, rpm_grid=rpm)
        med[fw] = post.limit_q_m[1] / a_sdm
        rc = post.recommended
        if fw == "sdm":
            assert np.all(post.limit_q_m[0] <= a_sdm) and np.all(a_sdm <= post.limit_q_m[2])
            # the recommended depth: the lower of the band's 5 % limit and held-out samples' own SDM 5 % limit
            assert rc["depth_m"] == min(rc["limit_p05_m"], rc["own_sdm_p05_m"]) and rc["p_stable"] >= 0.95
            assert rc["own_sdm_held_out"] is True  # 150 of the 300 samples are not the lobe samples
        else:
            assert rc["own_sdm_p05_m"] is None and rc["depth_m"] == rc["limit_p05_m"]
    assert np.all(np.abs(med["sdm"] - 1) < 0.1), med
    assert np.all(np.abs(med["zoa"] - 1) > 0.15), med
    # before any cut the prior's lobes are corrected the same way (the first cut's risk is the SDM's)
    pri = {fw: update(pr, [], rng=np.random.default_rng(0), n_samples=300, lobe_samples=150, forward=fw, sdm_refs=2,
                      rpm_grid=rpm).limit_q_m[1] / a_sdm for fw in ("zoa", "sdm")}
    assert np.all(np.abs(pri["sdm"] - 1) < 0.1) and np.all(np.abs(pri["zoa"] - 1) > 0.15), pri


def test_a_campaign_makes_each_cut_as_long_as_proposed(monkeypatch):
    """The virtual shop cuts as a user who follows every proposal does: for at least the proposal's
    ``duration_s`` (the CLI prints "for at least … s"), not only where ``audible_margin`` lengthened it. Until
    2026-12-01 it cut its usual length unless the proposal was lengthened, so after a 3.5 s cut the next proposal
    (the cuts' median, 3.5 s) was made in 0.9 s: the benchmark's campaigns alternated long and short cuts."""
    import toolpoint.shop.campaign as campaign

    proposed, made = [], []
    real_update = campaign.update

    def spy_update(*a, **k):
        post = real_update(*a, **k)
        proposed.append(post.next_cut["duration_s"])
        return post

    pr = cornelius_2024(0.1)
    inner = campaign.zoa_shop(pr)

    def shop(theta, rpm, depth_m, rng, duration_s=None):
        made.append(duration_s)
        return replace(inner(theta, rpm, depth_m, rng), duration_s=duration_s)

    monkeypatch.setattr(campaign, "update", spy_update)
    r = virtual_campaign(pr, rng=np.random.default_rng(1), shop=shop, stop=False, max_cuts=3, n_samples=200,
                         lobe_samples=100, forward="zoa", cut_duration_s=2.0)
    assert len(r.cuts) == 3 and made == proposed[:3], (made, proposed)
    # 2 s before the first cut (cut_duration_s), then the cuts' own median: never the shop's usual length
    assert all(d is not None and d >= 2.0 for d in made), made


@pytest.mark.slow  # ~3 s: two virtual campaigns (the fast tier kept under 3 min)
def test_a_campaign_without_a_stop_makes_the_same_cuts_and_reports_calibration():
    """``stop=False`` (the benchmark's calibration runs): the same cuts as a campaign that stops, up to its stop,
    the same ``converged_after``, and per update whether the truth lies under the recommended depth (checked here
    against the band and the truth's own zero-order limit) and the coverage near and away from the cut speeds."""
    from toolpoint.shop.update import _limits

    pr = cornelius_2024(0.1)
    kw = dict(max_cuts=4, n_samples=200, lobe_samples=100, label_offset=(0, 0), label_growth=(0, 0),
              forward="zoa")
    a = virtual_campaign(pr, rng=np.random.default_rng(1), **kw)
    b = virtual_campaign(pr, rng=np.random.default_rng(1), stop=False, **kw)
    assert a.converged_after == b.converged_after is not None and len(b.cuts) == 4
    assert b.cuts[:a.converged_after] == a.cuts and b.coverage[:len(a.coverage)] == a.coverage
    assert a.chatter_cuts == b.chatter_cuts == sum(not c.stable for c in a.cuts)
    assert len(b.below_recommended) == len(b.coverage_near) == len(b.coverage_away) == 5
    assert np.isnan(b.coverage_near[0]) and b.coverage_away[0] == b.coverage[0]
    # the first update, replayed in the campaign's random order (the truth is drawn first): its recommendation
    # against the truth's zero-order limit at the recommended speed
    rng = np.random.default_rng(1)
    rng.standard_normal(pr.sigma.size)
    post = update(pr, [], rng=rng, forward="zoa", n_samples=200, lobe_samples=100, label_offset=(0, 0),
                  label_growth=(0, 0))
    truth = _limits(pr, b.theta_true[None, :], pr.freq_grid(), post.rpm)[0]
    j = int(np.argmin(np.abs(post.rpm - post.recommended["rpm"])))
    assert b.below_recommended[0] == bool(truth[j] < post.recommended["depth_m"])
    q = post.limit_q_m
    assert b.coverage[0] == pytest.approx(np.mean((q[0] <= truth * 1.0000001) & (truth <= q[2] * 1.0000001)))
    for near, away, cov in zip(b.coverage_near[1:], b.coverage_away[1:], b.coverage[1:]):
        assert 0 <= near <= 1 and 0 <= away <= 1 and min(near, away) <= cov + 1e-12 <= max(near, away) + 2e-12
    # the map's P(chatter) at the truth's limit: under the 5 % line it claims under 0.05, over the 95 % over 0.95
    pit = b.p_chatter_at_truth[0]
    assert len(b.p_chatter_at_truth) == 5 and pit.shape == truth.shape
    np.testing.assert_allclose(pit, post.p_chatter(truth), atol=1e-12)
    assert np.all(pit[truth * 1.0000001 < q[0]] <= 0.05 + 1e-9) and np.all(pit[truth > q[2] * 1.0000001] >= 0.95)
    assert len(b.next_p_chatter) == 4 and b.next_p_chatter[0] == post.next_cut["p_chatter"]
    # the printed parameter ranges against the truth: the share of the posterior's parameter samples under it
    rank = (post.parameter_samples < b.theta_true[None, :]).mean(axis=0)
    np.testing.assert_allclose(b.parameter_rank[0], np.where(pr.sigma > 0, rank, np.nan), atol=0, equal_nan=True)
    q = post.parameter_quantiles()
    for k, name in enumerate(pr.names):  # inside the printed 5–95 % range where the rank lies within 0.05–0.95
        if pr.sigma[k] > 0 and 0.06 < rank[k] < 0.94:
            assert q[name][1][0] <= b.theta_true[k] <= q[name][1][2], (name, rank[k])


def test_cli_update_says_when_a_cut_lies_off_the_lobes_or_its_chatter_off_the_modes(tmp_path, capsys):
    """A cut at 40000 rpm on a prior drawn over 5000–25000 rpm, and a chatter frequency of 50 kHz (a kHz slip, or a
    machine's line) on modes at 1243 and 1747 Hz: both counted, both said on one line each naming the table's line;
    a chatter frequency on a tooth-passing alias of a mode (1747 + 1333 Hz at 20000 rpm, 4 teeth) is not."""
    prior = tmp_path / "prior.toml"
    prior.write_text(PRIOR_TOML)
    p = tmp_path / "cuts.csv"
    p.write_text("rpm,depth_mm,result,chatter_hz\n40000,0.5,stable,\n20000,0.9,chatter,50000\n"
                 "20000,0.95,chatter,3080\n")
    assert main([*UPDATE_ZOA, "--prior", str(prior), "--cuts", str(p), "--out", str(tmp_path / "o"),
                 "--samples", "300"]) == 0
    err = [w for w in capsys.readouterr().err.splitlines() if "warning" in w]
    assert len(err) == 2, err
    assert "line 2" in err[0] and "outside the speeds of the lobes" in err[0]
    assert "line 3" in err[1] and "50000.0 Hz lies far from every mode" in err[1]


def test_a_record_at_another_speed_than_its_row_s_rpm(tmp_path):
    """A row's rpm and its record's speed disagree (an override, a slipping belt, a typo). Beyond ``cut``'s search
    range (±3 %) the record is judged at a speed it did not run at: before, a stable cut at 6000 rpm given as 6600 read
    "chatter" (its own tooth passing at 400 Hz, 36 dB out) and sat at 6600 rpm in the lobes with a warning; now the row
    is refused, naming both speeds, unless its result confirms the record's reading (heavy chatter at the right speed
    makes such a comb on an accelerometer). Within the range, the cut is placed at the speed the record ran at, and
    said so."""
    import soundfile as sf

    from shop_synth import shop_record

    for name, chat in (("s.wav", None), ("c.wav", 1234.0)):
        x, rate, *_ = shop_record(rpm=6000.0, teeth=4, cut_s=2.0, chatter_hz=chat, chatter_amp=0.5, seed=3)
        sf.write(tmp_path / name, (0.5 * x / np.abs(x).max()).astype(np.float32), int(rate))
    p = tmp_path / "cuts.csv"
    for rpm in (6600, 5400):
        p.write_text(f"rpm,depth_mm,result,record\n6000,1.0,,c.wav\n{rpm},0.5,,s.wav\n")
        said = (rf"line 3: its record s.wav ran at 600\d rpm by its tooth-passing harmonics \([-+]\d+\.\d % from the "
                rf"table's {rpm} rpm\), and its 'chatter' at 400\.\d Hz is a tooth-passing harmonic of 600\d rpm")
        with pytest.raises(InputError, match=said) as exc:
            read_test_cuts(p, teeth=4)
        assert exc.value.field == "rpm"
    # the row's result confirms the record's reading: kept, with cut's warning of the other speed
    p.write_text("rpm,depth_mm,result,record\n6600,0.5,chatter,s.wav\n")
    (c,) = read_test_cuts(p, teeth=4)
    assert not c.stable and c.rpm == 6600 and any("6002 rpm" in w for w in c.warnings), c.warnings
    p.write_text("rpm,depth_mm,result,record\n6120,1.0,,c.wav\n5900,0.5,,s.wav\n6010,0.6,,s.wav\n")
    cuts = read_test_cuts(p, teeth=4)
    assert [c.stable for c in cuts] == [False, True, True]
    assert [c.rpm for c in cuts[:2]] == [pytest.approx(6000.0, rel=1e-3)] * 2 and cuts[2].rpm == 6010
    assert "ran at 6000 rpm, -2.0 % from the table's 6120 rpm" in cuts[0].warnings[0]
    assert "+1.7 % from the table's 5900 rpm" in cuts[1].warnings[0] and cuts[2].warnings == ()
    # the CLI: one line, exit 2, nothing written
    p.write_text("rpm,depth_mm,result,record\n6600,0.5,,s.wav\n")
    out = tmp_path / "out"
    assert main(["update", "--prior", str(Path(__file__).parents[2] / "examples" / "shop" / "cornelius_prior.toml"),
                 "--cuts", str(p), "--out", str(out)]) == 2
    assert not out.exists()


@pytest.mark.slow  # ~5 s: the lobe samples' own SDM limits (the fast tier kept under 3 min)
def test_the_band_at_the_pocket_is_made_of_the_lobe_samples_own_sdm_limits():
    """Before any cut (``forward="sdm"``): at the speeds ``own_pocket`` names, about the most productive one, the band's
    5 / 50 / 95 % are those of the lobe samples' own SDM limits — against an independent full search
    (:func:`sdm_lobes`) of ``lobe_z``'s there, within 3 % — and not of their zero-order limits times the references'
    ratio (the band with ``own_pocket=0``, whose upper line lay 10 % under the samples' own on EM16-50)."""
    from toolpoint.stability import sdm_lobes

    pr = cornelius_2024(0.1)
    post = update(pr, [], rng=np.random.default_rng(2), n_samples=300, lobe_samples=60, own_pocket=3)
    u = np.array(post.own_pocket_rpm)
    assert u.size >= 3 and u.min() <= post.recommended["rpm"] <= u.max(), (u, post.recommended)
    th = pr.theta(post.lobe_z[:, :pr.sigma.size])
    own = np.array([sdm_lobes(mm, mm, cut, rpm=u).depth_m for mm, cut in map(pr.tool, th)])  # (60, 3)
    for k, r in enumerate(u):
        j = int(np.argmin(np.abs(post.rpm - r)))
        # at the levels the band was read at (widened for its Monte Carlo noise: _band_levels)
        lv = [post.band_levels[0, j], 0.5, post.band_levels[1, j]]
        np.testing.assert_allclose(post.limit_q_m[:, j], np.quantile(own[:, k], lv), rtol=0.03)
    for bad in (-1, 2.5, 51, "five"):
        with pytest.raises(InputError, match="own_pocket"):
            update(pr, [], rng=np.random.default_rng(0), n_samples=300, lobe_samples=60, own_pocket=bad)
