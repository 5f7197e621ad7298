"""A chattering cut's growth rate: read from records against the semi-discretisation (a second method), refused
where a record has no single rate, carried by the test-cut table, and what the update makes of it."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.shop.campaign import microphone_record
from toolpoint.shop.detect import analyse_cut
from toolpoint.shop.growth import chatter_growth
from toolpoint.shop.model import cornelius_2024, growth_rate, limit_at_speeds, sdm_limits
from toolpoint.shop.update import GROWTH_ERROR, TestCut, log_likelihood, read_test_cuts, update

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from milling_sim import microphone  # noqa: E402


def _tone(rate, dur, sigma, f0=1030.0, spindle_hz=100.0, noise=0.01, seed=0, accel=0.0, t0=0.0, t_off=np.inf):
    """A chatter tone growing as e^{σ t + q t²} from 1e-3 at t0 s to a saturation at 1 (down to 1e-3 of that from t_off
    s, the tool leaving), over a spindle comb and white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(dur * rate)) / rate
    u = np.maximum(t - t0, 0.0)
    amp = 1e-3 * np.exp(np.minimum(sigma * u + accel * u * u, math.log(1e3))) * np.where(t > t_off, 1e-3, 1.0)
    comb = sum(np.sin(2 * np.pi * k * spindle_hz * t + k) / k for k in range(1, 20))
    return amp * np.sin(2 * np.pi * f0 * t) + comb + noise * rng.standard_normal(t.size), t


@pytest.mark.parametrize("sigma", [5.0, 30.0, 80.0])
def test_a_clean_exponential_rise_is_read(sigma):
    """From 1e-3 to 1 after 0.3 s of a quiet cut; at 6000 rpm and 2 teeth the windows are 12.5 ms (1/B, B = 80 Hz),
    so e^{6.9} at 80 /s takes 7 of them (at 150 /s, 3.7: refused as too fast)."""
    rate = 20000.0
    y, _ = _tone(rate, 1.5 + 8.0 / sigma, sigma, t0=0.3)
    g = chatter_growth(y, rate, rpm=6000.0, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=y.size / rate)
    assert g.rate_per_s == pytest.approx(sigma, rel=0.1), g
    assert g.rise_ln > math.log(3.0)


def test_a_chatter_that_falls_as_the_tool_leaves_is_read():
    """The cut's span ends with its exit, where the chatter drops: that dip is no foot of a rise (it once made such a
    record "rose within 0 windows")."""
    rate = 20000.0
    y, _ = _tone(rate, 2.0, 30.0, t0=0.3, t_off=1.9)
    g = chatter_growth(y, rate, rpm=6000.0, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=2.0)
    assert g.rate_per_s == pytest.approx(30.0, rel=0.1), g


def test_records_without_one_rate_are_refused():
    rate = 20000.0
    # a rise that accelerates, as a cut whose depth ramps up: e^{q t²}, its rate from 1 /s to 30 /s
    y, _ = _tone(rate, 2.0, 1.0, accel=7.25)
    g = chatter_growth(y, rate, rpm=6000.0, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=2.0)
    assert g.rate_per_s is None and "accelerates" in g.reason
    # chatter there from the start: nothing quiet before it
    y, _ = _tone(rate, 2.0, 1000.0)
    g = chatter_growth(y, rate, rpm=6000.0, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=2.0)
    assert g.rate_per_s is None and "already there" in g.reason
    # a step (a change of engagement): no growth to read
    y, t = _tone(rate, 2.0, 0.0)
    y = y + np.where(t > 1.0, 1.0, 0.0) * np.sin(2 * np.pi * 1030.0 * t)
    g = chatter_growth(y, rate, rpm=6000.0, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=2.0)
    assert g.rate_per_s is None and "at once" in g.reason


@pytest.mark.parametrize("rpm, x", [(11000.0, 0.05), pytest.param(19000.0, 0.15, marks=pytest.mark.slow)])
def test_simulated_cuts_give_the_semi_discretisation_s_rate(rpm, x):
    """Second method: a cut simulated in the time domain (Cornelius case) at a = a_SDM e^x, heard by the campaign's
    microphone and by the tests' shop microphone (fans, spindle lines, pink noise), read by `cut` — against the SDM's
    ln ρ / T. Over 60 such cuts (benchmarks/bench_growth.py --only estimator) the readings were 0.89–0.91× the SDM's
    at the median; these two within 0.7–1.1×."""
    from toolpoint.simulation import sensor_signal, simulate_milling
    from toolpoint.stability.sdm import sdm_spectral_radius

    pr = cornelius_2024(0.1)
    th = pr.theta(np.zeros((1, pr.sigma.size)))[0]
    mm, cut = pr.tool(th)
    a = sdm_limits(pr, th, [rpm], chatter=False)[0][0] * math.exp(x)
    ref = math.log(float(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a))) * cut.teeth * rpm / 60.0
    res = simulate_milling(mm, mm, cut, rpm=[rpm], depth_m=[a], revolutions=250, seed=3, seed_level=0.01)
    rng = np.random.default_rng(1)
    _, v = sensor_signal(res, 0, kind="microphone", rate=44100.0, noise=0.0)
    t = res.time_s[0] - res.time_s[0][0]
    d, f = res.displacement_m[0], res.force_n[0]
    shop, rate, *_ = microphone((t, d[:, 0], d[:, 1], f[:, 0], f[:, 1]), rpm=rpm, teeth=cut.teeth, seed=2)
    for y in (microphone_record(v, 44100.0, rng), shop):
        r = analyse_cut(y, 44100.0, rpm=rpm, teeth=cut.teeth, full_scale=1.0)
        assert r.verdict == "chatter" and r.growth is not None
        assert 0.7 < r.growth.rate_per_s / ref < 1.1, (r.growth, ref)
        assert r.to_dict()["growth"]["rate_per_s"] == pytest.approx(r.growth.rate_per_s, abs=1e-3)


def test_the_table_carries_the_growth_rate(tmp_path):
    p = tmp_path / "cuts.csv"
    p.write_text("rpm,depth_mm,result,chatter_hz,growth_per_s\n12000,0.4,chatter,1280,35\n10000,0.2,stable,,\n")
    cuts = read_test_cuts(p)
    assert cuts[0].growth_per_s == 35.0 and cuts[1].growth_per_s is None
    for bad, what in (("10000,0.2,stable,,5", "a stable cut has no chatter growth"), ("12000,0.4,chatter,,1e6",
                                                                                         "not a chatter's growth")):
        p.write_text("rpm,depth_mm,result,chatter_hz,growth_per_s\n" + bad + "\n")
        with pytest.raises(InputError, match=what) as e:
            read_test_cuts(p)
        assert e.value.field == "growth_per_s"


def test_the_rate_says_how_far_past_the_limit_the_cut_was():
    """A chattering cut at a known distance past the truth's limit, with the rate the truth predicts: the posterior
    puts the limit at that speed within the band about the truth, and a cut read as growing 5× faster moves it down
    (further past); a rate the samples cannot explain (a cut below their limit) counts as an outlier, not as −∞."""
    pr = cornelius_2024(0.1)
    z = np.random.default_rng(4).standard_normal((1, pr.sigma.size))
    th = pr.theta(z)
    rpm = 12000.0
    a_lim, fc = limit_at_speeds(pr, th, [rpm])
    kap = growth_rate(pr, th, [rpm], fc)[0, 0]
    depth = float(a_lim[0, 0]) * math.exp(0.15)
    quant = {}
    b = GROWTH_ERROR[0]
    for name, sig in (("none", None), ("right", b * kap * 0.15), ("fast", 5 * b * kap * 0.15)):
        post = update(pr, [TestCut(rpm, depth, False, float(fc[0, 0]), growth_per_s=sig)], rng=np.random.default_rng(0),
                      n_samples=600, lobe_samples=150, forward="zoa")
        lim = limit_at_speeds(pr, post.theta, [rpm])[0][:, 0]
        quant[name] = np.quantile(np.log(depth / lim), [0.05, 0.5, 0.95])
    lo, med, hi = quant["right"]
    assert lo < 0.15 < hi and abs(med - 0.15) < 0.1, quant
    assert hi - lo < 0.7 * (quant["none"][2] - quant["none"][0]), quant  # the rate narrows it
    # 5× the rate says 0.75 past, in the prior's tail (its 95 % is 0.53): the median moves past the right one's 95 %
    assert quant["fast"][1] > hi and quant["fast"][2] > quant["none"][2], quant
    ll = log_likelihood(pr, th, [TestCut(rpm, 0.5 * depth, False, None, growth_per_s=50.0)], growth_error=GROWTH_ERROR)
    assert np.isfinite(ll).all()


def test_a_rate_where_the_sdm_limit_is_another_lobe_is_left_out():
    """Without the SDM's growth curves (``forward="zoa"``, or a caller's ``log_ratio`` alone): where the SDM correction
    at a cut exceeds 10 % its limiting lobe may be another than the zero-order's, whose κ the term uses (EM12-60: κ x
    against the SDM's rate 0.07–1.6 there): the rate leaves the likelihood as it was. (``update``'s SDM path reads
    it through the curves instead: the next test.)"""
    pr = cornelius_2024(0.1)
    th = pr.sample(50, np.random.default_rng(2)).theta
    with_rate = [TestCut(12000.0, 0.5e-3, False, 1280.0, growth_per_s=40.0)]
    without = [TestCut(12000.0, 0.5e-3, False, 1280.0)]
    for lr, same in ((0.05, False), (-0.05, False), (0.15, True), (-0.3, True)):
        a = log_likelihood(pr, th, with_rate, log_ratio=[lr], growth_error=GROWTH_ERROR)
        b = log_likelihood(pr, th, without, log_ratio=[lr], growth_error=GROWTH_ERROR)
        assert np.array_equal(a, b) == same, lr


def test_the_sdm_s_own_growth_reads_the_distance_past_a_pocket_s_limit():
    """Where the SDM's limit lies far from the zero-order one (8500 rpm on the Cornelius tool: ln ratio 0.56), the
    rate is read by the SDM's own growth curve at reference samples near the truth: a cut 12 % past the truth's SDM
    limit, with the SDM's own σ there (ln ρ / T, at a depth off the curve's grid), reads x within 0.02, where the
    zero-order κ would say 0.09 (27 % short), measured from the curve's own zero crossing; a rate past the curve's
    reach, or a curve already unstable at its start, is no reading, nor is a rate heard on a line that no reference
    grows there; and in the likelihood the term favours the samples that put the cut x_m past their limit."""
    from toolpoint.shop.update import _fold_hz, _sdm_growth_x
    from toolpoint.stability.sdm import sdm_spectral_radius

    pr = cornelius_2024(0.1)
    z0 = np.zeros((1, pr.sigma.size))
    th = pr.theta(z0)
    rpm, x = 8500.0, 0.12
    a_s = sdm_limits(pr, th[0], [rpm], chatter=False)[0][0]
    a_z, fz = limit_at_speeds(pr, th, [rpm])
    mm, cut = pr.tool(th[0])
    ft = cut.teeth * rpm / 60.0
    sig = math.log(float(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a_s * math.exp(x)))) * ft
    kz = growth_rate(pr, th, [rpm], fz)[0, 0]
    assert abs(sig / kz - x) > 0.025  # the zero-order κ misreads it here (0.088)
    # references as a posterior pinned near the truth would give: close to it, each with its own SDM limit
    ref_z = z0 + 0.03 * np.random.default_rng(5).standard_normal((4, pr.sigma.size))
    ref = pr.theta(ref_z)
    lr = np.log(np.array([[sdm_limits(pr, t, [rpm], chatter=False)[0][0]] for t in ref])
                / limit_at_speeds(pr, ref, [rpm])[0])
    cuts = [TestCut(rpm, a_s * math.exp(x), False, None, growth_per_s=sig),
            TestCut(rpm, a_s * math.exp(x), False, None, growth_per_s=100 * sig),  # past x = 1
            TestCut(rpm, 0.9 * a_s, True, None)]
    xm, sd = _sdm_growth_x(pr, ref, cuts, np.repeat(lr, 3, axis=1), pr.freq_grid())
    assert abs(xm[0] - x) < 0.02 and sd[0] < 0.02, (xm, sd)
    assert np.isnan(xm[1]) and np.isnan(xm[2])
    # x is read from the curve's own zero crossing, not from where the references' search put the limit: from the
    # zero-order limit (lr 0, the SDM's 0.56 above it, within the curve's reach) the same x; from a limit put 1.5
    # above the zero-order one (past the SDM's: unstable already at the curve's start) no reading
    xm0, _ = _sdm_growth_x(pr, ref, cuts[:1], np.zeros((4, 1)), pr.freq_grid())
    assert abs(xm0[0] - x) < 0.02, xm0
    xm1, _ = _sdm_growth_x(pr, ref, cuts[:1], np.full((4, 1), 1.5), pr.freq_grid())
    assert np.isnan(xm1[0])
    # a reference reads a rate only where what grows on its curve at the reading is the chatter heard (the heard
    # frequency folded by the tooth-passing frequency, _fold_hz, against ±arg μ f_t / 2π of its critical multiplier
    # there). The line heard: the SDM's chatter frequency at the truth's limit, computed apart (sdm_limits: the
    # strongest line of the critical eigen-solution, not the multiplier's angle) — then the reading is the same as
    # with no frequency stated, also for its alias one f_t up; a line of the tool's other mode (1747 Hz, its fold
    # 212 Hz off) is another mode's chatter, which no reference grows there: no reading. (EM12-60's truth 48
    # chattered at 1648 Hz, an alias of its 762 Hz mode, growing at 7.4 /s 0.46 past its limit; its references grew
    # another line there and read 0.01, and the band after that cut, 2.58–3.02 mm, missed the truth's 1.85 mm.)
    f_s = sdm_limits(pr, th[0], [rpm])[1][0]
    mu0 = complex(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a_s * 1.001, multiplier=True))
    assert abs(float(_fold_hz(f_s, ft)) - abs(np.angle(mu0)) / (2 * np.pi) * ft) < 0.002 * f_s  # the two agree
    # past the limit the line moves (by 16 Hz, 1.1 %, at x = 0.12 here): within the 3 % the gate allows
    other = 1747.0
    assert abs(float(_fold_hz(other, ft)) - float(_fold_hz(f_s, ft))) > 0.03 * other
    heard = [TestCut(rpm, a_s * math.exp(x), False, hz, growth_per_s=sig) for hz in (f_s, f_s + ft, other)]
    xh, sdh = _sdm_growth_x(pr, ref, heard, np.repeat(lr, 3, axis=1), pr.freq_grid())
    assert xh[0] == xm[0] and xh[1] == xm[0], (xh, xm)
    assert np.isnan(xh[2]) and np.isnan(sdh[2])
    # in the likelihood: the term (with the rate − without) is largest for the samples that put the cut x_m past
    # their (corrected) limit, and falls off on either side
    ths = pr.sample(200, np.random.default_rng(6)).theta
    lr3 = [math.log(a_s / a_z[0, 0])]
    kw = dict(log_ratio=lr3, growth_error=GROWTH_ERROR, growth_x=(xm[:1], sd[:1]))
    term = log_likelihood(pr, ths, cuts[:1], **kw) - log_likelihood(
        pr, ths, [TestCut(rpm, a_s * math.exp(x), False, None)], **kw)
    xs = np.log(a_s * math.exp(x)) - np.log(limit_at_speeds(pr, ths, [rpm])[0][:, 0]) - lr3[0]
    near = np.abs(xs - xm[0]) < 0.03
    far = np.abs(xs - xm[0]) > 0.2
    assert near.any() and far.any()
    assert term[near].min() > term[far].max()


@pytest.mark.slow  # 5–8 s: the fast tier stays under 3 min
def test_the_update_says_how_far_past_the_limit_each_rate_read(tmp_path):
    """``forward="sdm"``: the posterior and update.json carry, per cut, the distance past the limit the SDM's growth
    curves read from its rate — for the chattering cut with a rate only, near where the truth's own curve puts it (a
    cut 8 % past the truth's SDM limit with the truth's σ, 38.7 /s at 20000 rpm: 0.073–0.085 over update seeds 0–2,
    from posterior references) — and nothing without the rates (``growth_error`` None) or under the zero-order
    model, whose κ x is per sample."""
    import json

    from toolpoint.shop.report import write_update

    pr = cornelius_2024(0.1)
    th = pr.theta(np.zeros((1, pr.sigma.size)))
    rpm = 20000.0
    mm, cut = pr.tool(th[0])
    a_s = sdm_limits(pr, th[0], [rpm], chatter=False)[0][0]
    from toolpoint.stability.sdm import sdm_spectral_radius

    sig = math.log(float(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a_s * math.exp(0.08)))) * cut.teeth * rpm / 60
    cuts = [TestCut(rpm, 0.9 * a_s, True), TestCut(rpm, a_s * math.exp(0.08), False, None, growth_per_s=sig)]
    kw = dict(n_samples=300, lobe_samples=100)
    post = update(pr, cuts, rng=np.random.default_rng(0), forward="sdm", **kw)
    assert post.growth_past_limit[0] is None and 0.05 < post.growth_past_limit[1] < 0.11, post.growth_past_limit
    write_update(post, tmp_path)
    doc = json.loads((tmp_path / "update.json").read_text())
    assert doc["cuts"][1]["growth_past_limit_ln"] == pytest.approx(post.growth_past_limit[1], abs=1e-4)
    assert "(x 0.0" in (tmp_path / "report.html").read_text()
    from toolpoint.cli.update import _growth_read  # the CLI's line, as the report's cell says it

    assert _growth_read(post, False) == f"cut 2: {sig:.3g} /s = {100 * math.expm1(post.growth_past_limit[1]):.1f} % " \
        "past the limit by the SDM's growth"
    for other in (dict(forward="sdm", growth_error=None), dict(forward="zoa")):
        assert update(pr, cuts, rng=np.random.default_rng(0), **kw, **other).growth_past_limit == (None, None)


def test_a_rate_that_is_no_growth_is_left_out():
    """A TestCut made in code (the table's reader refuses these) with a rate ≤ 0 or not finite leaves the likelihood
    as the label alone, in both the zero-order and the SDM-curve terms."""
    pr = cornelius_2024(0.1)
    th = pr.sample(50, np.random.default_rng(2)).theta
    without = log_likelihood(pr, th, [TestCut(12000.0, 0.5e-3, False, 1280.0)], growth_error=GROWTH_ERROR)
    for bad in (-5.0, 0.0, float("nan"), float("inf")):
        cut = [TestCut(12000.0, 0.5e-3, False, 1280.0, growth_per_s=bad)]
        assert np.array_equal(log_likelihood(pr, th, cut, growth_error=GROWTH_ERROR), without), bad
        gx = (np.array([0.1]), np.array([0.01]))
        assert np.array_equal(log_likelihood(pr, th, cut, growth_error=GROWTH_ERROR, growth_x=gx), without), bad
