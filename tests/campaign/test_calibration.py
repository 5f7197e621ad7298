"""The predictive uncertainty of learned joint parameters: cross-validated, calibrated out of sample.

Independent checks: the held-out coverage of the 90 % interval is counted on tools drawn afresh from the law
that made the campaign (never seen by learn), for a law an ANFIS fits better than a power law and for one a
power law fits; a rarely identified parameter falls back to the campaign's spread; an over-fitted ANFIS is
not trusted.
"""

import json

import numpy as np
import pytest

from campaign.test_campaign_learn import identified_rows, write_identified
from toolpoint.campaign import calibration
from toolpoint.campaign.learn import auto_test_size, learn
from toolpoint.errors import InputError

QUIET = dict(baselines=False, plots=False)


def _bump(D, L):
    """A kt law no power law fits: a saturating rise in D with a dip around L = 50 mm (a holder's sweet spot)."""
    return 2e7 * np.tanh(D / 14.0) * (1 + 0.25 * np.exp(-(((L - 50) / 12) ** 2)))


def _rows(law, n, seed, noise=0.01):
    rows = identified_rows(n=n, n_failed=0, seed=seed, noise=0.0)
    rng = np.random.default_rng(seed + 100)
    for r in rows:
        v = law(float(r["diameter_mm"]), float(r["overhang_mm"])) * (1 + noise * rng.standard_normal())
        r["kt"], r["kt_lo"], r["kt_hi"] = repr(float(v)), repr(float(0.97 * v)), repr(float(1.03 * v))
    return rows


def _coverage_on_fresh_tools(models, law, n=400, seed=7, noise=0.01):
    """Share of fresh tools (D, L inside the campaign's range) whose identified kt lies in the 90 % interval."""
    from toolpoint.campaign.distribution import JointPredictor

    rng = np.random.default_rng(seed)
    D, L = rng.uniform(9, 30, n), rng.uniform(16, 83, n)
    truth = np.log10(law(D, L) * (1 + noise * rng.standard_normal(n)))
    dist = JointPredictor(models).predict(D, L)
    z = np.abs(truth - dist.log10_median[:, 0]) / dist.sigma_log10[:, 0]
    return float(np.mean(z <= 1.6448536269514729)), dist


def test_conformal_interval_holds_out_of_sample():
    """Residuals of any shape (here Student-t, 3 dof): the calibrated 90 % interval holds ≈ 90 % of new ones."""
    rng = np.random.default_rng(0)
    n = 200
    X = np.column_stack([rng.uniform(9, 30, n), rng.uniform(16, 83, n)])
    r = 0.05 * rng.standard_t(3, n)
    fold = calibration.fold_ids(n, 5, 0)
    trained = {k: X[fold != k] for k in range(5)}
    u = calibration.fit_uncertainty("kt", X, r, fold, trained, X, X.min(0), X.max(0), (6.0, 9.0),
                                    10 ** (7 + 0.3 * rng.standard_normal(n)))
    assert u.kind == "model" and 0.85 <= u.cv["coverage90"] <= 0.95
    new = 0.05 * rng.standard_t(3, 20000)
    Xn = np.column_stack([rng.uniform(9, 30, 20000), rng.uniform(16, 83, 20000)])
    held = np.mean(np.abs(new) <= 1.6448536269514729 * u.sigma(Xn))
    assert 0.88 <= held <= 0.97  # sparsity only widens: at least the nominal 90 %, not uselessly more
    # wider outside the learned range: 10 % of the range beyond it → ×1.5
    assert u.scale([[30 + 2.1, 50]])[0] >= 1.5 * u.scale([[30, 50]])[0]


def test_anfis_chosen_and_calibrated_on_a_law_no_power_law_fits(tmp_path):
    res = write_identified(tmp_path / "bump", _rows(_bump, 120, 3))
    r = learn(res, mfs=(2, 3), targets=["kt"], **QUIET)
    u = r.uncertainty["kt"]
    assert u["kind"] == "model", u["reason"]
    assert 0.8 <= u["coverage90"] <= 0.97
    cov, _ = _coverage_on_fresh_tools(res / "models", _bump)
    assert 0.8 <= cov <= 0.99, cov  # the interval printed as 90 % holds on tools learn never saw


def _power(D, L):
    return 2e7 * (D / 16) ** 1.5 * (L / 50) ** -0.15


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_overfitted_anfis_loses_to_the_power_law(tmp_path, seed):
    """The 3×7 grid on 40 tools over-fits (training error ≈ 0): its held-out error decides, not its training one."""
    res = write_identified(tmp_path / "small", _rows(_power, 40, seed))
    r = learn(res, mfs=(3, 7), targets=["kt"], **QUIET)
    assert r.n_test == auto_test_size(40) == 7  # a 40-tool campaign is not starved by a fixed 30-tool test set
    u = r.uncertainty["kt"]
    assert u["kind"] == "powerlaw" and "chosen over the ANFIS" in u["reason"]
    cov, _ = _coverage_on_fresh_tools(res / "models", _power)
    # one 40-tool campaign's interval rests on 40 residuals: its coverage of fresh tools varies by ±5–10 points
    # around the nominal 90 % (measured 80.5, 90.3 and 85.3 % for seeds 4–6); 80 tools below hold it tighter
    assert cov >= 0.75


def test_power_law_interval_holds_on_fresh_tools(tmp_path):
    covs = []
    for seed in (4, 5, 6):
        res = write_identified(tmp_path / f"s{seed}", _rows(_power, 80, seed))
        learn(res, mfs=(2, 2), targets=["kt"], epochs=30, **QUIET)
        covs.append(_coverage_on_fresh_tools(res / "models", _power)[0])
    assert 0.85 <= np.mean(covs) <= 0.97, covs


def test_rarely_identified_parameter_takes_the_campaign_spread_clipped(tmp_path):
    rows = identified_rows(n=80, n_failed=0, seed=2)
    res = write_identified(tmp_path / "r", rows)
    r = learn(res, mfs=(2, 2), epochs=30, **QUIET)
    u = r.uncertainty["cr"]  # identified in 1 row of 12
    assert u["kind"] == "spread" and "identified in only" in u["reason"]
    doc = json.loads((res / "models" / calibration.FILE_NAME).read_text())["parameters"]["cr"]
    values = np.log10([float(x["cr"]) for x in rows])
    assert doc["centre_log10"] == pytest.approx(np.median(values))
    assert doc["sigma_log10"] == pytest.approx(np.std(values, ddof=1))
    lo = np.log10(min(float(x["cr_lo"]) for x in rows))
    assert doc["clip_log10"][0] == pytest.approx(min(lo, 0.0))  # the search bounds (1 N m s/rad), or wider

    from toolpoint.campaign.distribution import JointPredictor

    dist = JointPredictor(res / "models").predict([60.0], [300.0])  # far outside: medians stay in range
    assert np.all(dist.log10_median >= dist.clip_log10[0]) and np.all(dist.log10_median <= dist.clip_log10[1])
    samples = dist.sample(0, 2000, np.random.default_rng(0))
    assert np.all(np.log10(samples) >= dist.clip_log10[0] - 1e-12)


def test_learn_prints_the_held_out_coverage(tmp_path, capsys):
    from toolpoint.cli.main import main

    res = write_identified(tmp_path / "c", identified_rows(n=60, n_failed=0))
    assert main(["campaign", "learn", str(res), "--mfs", "2,2", "--epochs", "20", "--no-baselines",
                 "--no-plots"]) == 0
    out = capsys.readouterr().out
    assert "held-out 90 % coverage" in out
    lines = out.splitlines()
    start = next(i for i, x in enumerate(lines) if "held-out 90 % coverage" in x)
    line = next(x for x in lines[start:] if x.startswith("kt "))
    assert "% of 60" in line  # every tool held out once


def test_bad_uncertainty_file_is_one_line(tmp_path):
    p = tmp_path / calibration.FILE_NAME
    p.write_text('{"format": "other"}')
    with pytest.raises(InputError) as err:
        calibration.read_uncertainty(p)
    assert "campaign learn" in str(err.value) and err.value.file == str(p)
    with pytest.raises(InputError):
        learn(write_identified(tmp_path / "x", identified_rows(n=60, n_failed=0)), cv_folds=1, **QUIET)


def test_samples_stay_where_the_nearby_frfs_bound_a_parameter(tmp_path):
    """kr identified only by the small tools (D ≤ 18 mm); the large tools' intervals run into the search bound
    above (their FRFs hardly depend on a stiff joint) and bound kr below only. A new large tool's kr samples stay
    above those bounds — below the truth, which the unbounded distribution spilled far under."""
    from toolpoint.campaign.distribution import JointPredictor

    rows = identified_rows(n=90, n_failed=0, seed=4)
    top = 1e9  # the search bound the open intervals run into
    for r in rows:
        if float(r["diameter_mm"]) > 18:
            v = float(r["kr"])
            r["kr"], r["kr_lo"], r["kr_hi"] = repr(float(3 * v)), repr(float(0.6 * v)), repr(top)  # value: anywhere
    res = write_identified(tmp_path / "r", rows)
    learn(res, mfs=(2, 2), epochs=30, **QUIET)
    doc = json.loads((res / "models" / calibration.FILE_NAME).read_text())["parameters"]["kr"]
    assert sum(v is not None for v in doc["window_lo"]) == sum(float(r["diameter_mm"]) > 18 for r in rows)
    pred = JointPredictor(res / "models")
    u = pred.parameters["kr"]
    D, L = np.array([26.0, 12.0]), np.array([50.0, 50.0])
    lo, hi = u.window(np.column_stack([D, L]))
    truth = np.log10(1.4e6 * (D / 16) ** 2.5)
    assert lo[0] < truth[0] and lo[0] > truth[0] - 0.3 and np.isneginf(lo[1]) and np.all(np.isposinf(hi))
    dist = pred.predict(D, L)
    s = np.log10(dist.sample(0, 4000, np.random.default_rng(1))[:, 2])
    assert s.min() >= lo[0] - 1e-12
    untruncated = dist.log10_median[0, 2] + dist.sigma_log10[0, 2] * np.random.default_rng(1).standard_normal(4000)
    assert np.mean(untruncated < lo[0]) > 0.2  # where the FRFs say kr cannot be
    q = np.log10(dist.quantiles([0.05, 0.5])[:, 0, 2])
    assert q[0] >= lo[0] - 1e-12 and q[1] >= dist.log10_median[0, 2]
    # the small tool, identified by its neighbours: not truncated
    s_small = np.log10(dist.sample(1, 4000, np.random.default_rng(1))[:, 2])
    z = (s_small - dist.log10_median[1, 2]) / dist.sigma_log10[1, 2]
    assert abs(np.mean(z)) < 0.1 and abs(np.std(z) - 1) < 0.1
    # written and read back as they were
    again = calibration.read_uncertainty(res / "models" / calibration.FILE_NAME)["kr"]
    assert np.allclose(again.window(np.column_stack([D, L]))[0][:1], lo[:1])
