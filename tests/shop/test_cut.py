"""``toolpoint cut``: chatter detection on synthetic shop records, on a real shop recording, bad input."""

import dataclasses
import functools
import json
import re
from pathlib import Path

import numpy as np
import pytest

from shop_synth import phone_agc, shop_record
from toolpoint.cli.main import main
from toolpoint.errors import InputError
from toolpoint.io.records import read_cut_record
from toolpoint.shop import analyse_cut, harmonizer_rpm

REAL = Path(__file__).resolve().parents[2] / "examples" / "cuts" / "combined_chatter6567.mp3"


@functools.cache
def _real_read():
    return read_cut_record(REAL)


def real_record():
    """The real recording as :func:`read_cut_record` reads it (the first test below checks that read), decoded once
    per worker (0.3–0.5 s a read, 15 tests): each test gets its own copy of the samples."""
    rec = _real_read()
    return dataclasses.replace(rec, samples=rec.samples.copy())


def _cut_segments(res):
    return [s for s in res.segments if s.kind == "cut"]


def test_stable_cut_with_fans_and_runout_is_stable():
    x, rate, t0, t1 = shop_record(rpm=6000, teeth=4, chatter_hz=None, mode_hz=1234.0, seed=1)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    assert res.verdict == "stable" and res.chatter_hz is None and res.recommended_rpm is None
    kinds = [s.kind for s in res.segments]
    assert kinds[0] == "air" and kinds[-1] == "air" and "entry" in kinds and "exit" in kinds
    # the segment bounds follow the tool going in and out (within a frame)
    entry = next(s for s in res.segments if s.kind == "entry")
    exit_ = next(s for s in res.segments if s.kind == "exit")
    assert abs(entry.start_s - t0) < 0.2 and abs(exit_.end_s - t1) < 0.2
    assert abs(res.rpm / 6000 - 1) < 1e-3


@pytest.mark.parametrize("rpm,teeth,fc", [(6000, 4, 1234.0), (9100, 2, 2620.0), (3150, 3, 812.0)])
def test_chatter_found_at_its_frequency(rpm, teeth, fc):
    x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=fc, chatter_amp=0.5, seed=2)
    # the nominal speed is 2 % off: the detector finds the spindle in the record
    res = analyse_cut(x, rate, rpm=rpm * 1.02, teeth=teeth, full_scale=1.0)
    assert res.verdict == "chatter"
    assert abs(res.chatter_hz / fc - 1) < 0.01
    assert abs(res.rpm / rpm - 1) < 2e-3
    # Harmonizer: a tooth-passing harmonic on the chatter frequency
    j = 60 * res.chatter_hz / (teeth * res.recommended_rpm)
    assert abs(j - round(j)) < 1e-9


@pytest.mark.parametrize("teeth", [4, 3])
def test_chatter_on_a_spindle_harmonic_is_found_by_its_excess_over_the_runout_lines(teeth):
    # 1000 Hz at 6000 rpm is the spindle harmonic 10 f_s: with 4 teeth a period doubling (flip, f_c = 2.5 f_t),
    # with 3 a chatter at a rotation of 1/3 per tooth period (f_c = (3 + 1/3) f_t); its aliases 1000 ∓ f_t are
    # harmonics of the same residue. Masked from the main test. shop_synth's runout raises every multiple of f_s
    # alike (non-tooth lines 0.1 (k/N)^-1.2 of the tooth line): the chatter line stands out of them.
    x, rate, *_ = shop_record(rpm=6000, teeth=teeth, chatter_hz=1000.0, chatter_amp=1.0, seed=5)
    res = analyse_cut(x, rate, rpm=6000, teeth=teeth, full_scale=1.0)
    assert res.verdict == "chatter" and abs(res.chatter_hz - 1000.0) < 1.0
    # 8 dB over its neighbours (what a runout line on a sharp mode does) is not chatter
    x, rate, *_ = shop_record(rpm=6000, teeth=teeth, chatter_hz=1000.0, chatter_amp=0.1, seed=5)
    assert analyse_cut(x, rate, rpm=6000, teeth=teeth, full_scale=1.0).verdict == "stable"


def test_with_two_teeth_chatter_on_a_runout_line_cannot_be_told():
    # the non-tooth harmonics of a 2-tooth cutter all share one residue: a flip line has no other runout line to
    # stand out of, and the detector does not guess
    x, rate, *_ = shop_record(rpm=12000, teeth=2, chatter_hz=1000.0, chatter_amp=1.0, seed=5)
    assert analyse_cut(x, rate, rpm=12000, teeth=2, full_scale=1.0).verdict == "stable"


def test_fan_tone_present_in_air_cut_is_not_chatter():
    # a loud fan line far above the cut's harmonics: there before the cut, so not chatter
    x, rate, *_ = shop_record(rpm=6000, teeth=4, fans=(1317.0,), fan_amp=3.0, seed=3)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    assert res.verdict == "stable"
    # the air cut is what refuses it: without the rise test the fan is taken for chatter
    blind = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0, rise_db=-np.inf)
    assert blind.verdict == "chatter" and abs(blind.chatter_hz - 1317.0) < 3


@pytest.mark.slow
def test_false_alarms_on_stable_cuts_are_rare():
    """Calibration of the tone test: stable records of many seeds and speeds, no chatter verdict."""
    rng = np.random.default_rng(7)
    wrong = 0
    for seed in range(20):
        rpm, teeth = float(rng.uniform(3000, 12000)), int(rng.integers(2, 5))
        x, rate, *_ = shop_record(rpm=rpm, teeth=teeth, air_s=1.0, cut_s=1.5, fans=tuple(rng.uniform(300, 4000, 2)),
                                  mode_hz=float(rng.uniform(500, 3000)), seed=100 + seed)
        res = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
        wrong += res.verdict != "stable"
    assert wrong <= 1


def test_harmonizer_rule():
    best, alts = harmonizer_rpm(1000.0, 4, 3300.0)
    assert best == pytest.approx(3000.0) and alts == pytest.approx((3750.0, 2500.0))
    # the nearest in ratio: from 14000 rpm with 2 teeth and 1500 Hz, j = 3 (15000 rpm) beats j = 4 (11250)
    assert harmonizer_rpm(1500.0, 2, 14000.0)[0] == pytest.approx(15000.0)


def test_real_shop_recording_air_entry_cut_chatter_exit():
    """A real shop microphone (UBC, MIT; examples/cuts/README.md): air cut, entry, cutting that chatters, exit.

    Speed and teeth are not documented: the audio's tooth-passing comb is at 215.3 Hz; a nominal
    6500 rpm and 2 teeth are given with a 5 % search range and the spindle is found in the record.
    """
    rec = read_cut_record(REAL)
    assert rec.rate_hz == 44100 and rec.channel == "mean of 2"
    res = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert abs(res.rpm * 2 / 60 - 215.3) < 0.3
    assert res.criterion["speed_elsewhere_rpm"] is None  # the tooth passing stands out at the speed found
    # its spindle runs faster out of the cut: the first two tooth-passing harmonics read 215.6–215.8 Hz at the
    # entry and the exit, 215.3 in the cut (peaks of 1.5 s frames, read by hand) — 0.1–0.2 %, more than the
    # mask's 0.05 %: tracked (the verdicts below are those of the fixed mask too)
    assert res.criterion["speed_tracked"] and 0.001 < res.criterion["speed_wander"] < 0.003
    kinds = [s.kind for s in res.segments]
    # air cut first and last, entry before the cut, exit after it
    assert kinds[0] == "air" and kinds[1] == "entry" and kinds[-2] == "exit" and kinds[-1] == "air"
    assert res.segments[0].end_s > 5.0 and res.segments[-1].start_s < 18.0
    cut = _cut_segments(res)
    assert res.verdict == "chatter"
    dur = {v: sum(s.end_s - s.start_s for s in cut if s.verdict == v) for v in ("stable", "chatter")}
    assert dur["chatter"] > dur["stable"]
    # stable cutting, then chatter, as the README says: once chatter starts it stays
    verdicts = [s.verdict for s in cut]
    first = verdicts.index("chatter")
    assert all(v == "chatter" for v in verdicts[first:])
    assert first > 0 and dur["stable"] > 1.0  # the source's stable cutting before the chatter
    # the cut's floor lies under the air cut's: recorded with some gain control, which `cut` says
    assert all(s.air_gain_db < 0 for s in cut)
    assert any("gain control" in w for w in res.criterion["warnings"])
    # the chatter frequency is one across segments: every chattering segment reports it or its 2nd harmonic
    # (where the fundamental sits on a spindle harmonic), within 1 %
    fc = res.chatter_hz
    assert 1040 < fc < 1090
    for s in cut:
        if s.verdict == "chatter":
            ratio = s.chatter_hz / fc
            assert min(abs(ratio - 1), abs(ratio / 2 - 1)) < 0.01, s
    long_chat = [s for s in cut if s.verdict == "chatter" and s.end_s - s.start_s > 2]
    assert long_chat and all(abs(s.chatter_hz / fc - 1) < 0.01 for s in long_chat)
    # its chatter rises 3 s after the entry, at 2.2 /s where a line is fitted by eye to the envelope over 9.95–10.85 s
    # (benchmarks/bench_growth.py --only real); that rise also fits a step in the level (at ~10.2 s, where the
    # spindle's 10th harmonic drops by 10 dB: the engagement may change there), so `cut` reads no rate, or a slow one
    g = res.growth
    assert g is not None and (g.rate_per_s is None and "at once" in g.reason or 1.0 < g.rate_per_s < 4.0), g
    # how long the tool cut, as a test-cut table's record gives it to `update` (chatter grows within one run): from
    # the entry's start to the exit's end, inside the two air cuts
    from toolpoint.shop.update import _cutting_s

    entry, exit_ = res.segments[1], res.segments[-2]
    assert _cutting_s(res) == pytest.approx(exit_.end_s - entry.start_s)
    assert res.cuts == ((entry.start_s, exit_.end_s, "chatter", fc),)  # one cut
    assert res.segments[0].end_s <= entry.start_s and exit_.end_s <= res.segments[-1].start_s


def test_cli_cut_writes_json_and_plot(tmp_path, capsys):
    import soundfile as sf

    x, rate, *_ = shop_record(rpm=6000, teeth=4, chatter_hz=1234.0, chatter_amp=0.5, seed=4)
    wav = tmp_path / "cut.wav"
    sf.write(wav, x, int(rate), subtype="PCM_16")
    out, png = tmp_path / "cut.json", tmp_path / "cut.png"
    assert main(["cut", str(wav), "--rpm", "6000", "--teeth", "4", "--out", str(out), "--plot", str(png)]) == 0
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "chatter" and abs(doc["chatter_hz"] / 1234 - 1) < 0.01
    assert {"start_s", "end_s", "verdict", "chatter_hz"} <= set(doc["segments"][0])
    assert doc["recommended_rpm"] > 0 and png.stat().st_size > 10_000
    # --dominance and --alias-dominance reach the criterion: a chatter line of a few % of the harmonic's power is
    # not "strong" at 100 — unless its tooth-passing aliases are there and --alias-dominance lets it through
    args = ["cut", str(wav), "--rpm", "6000", "--teeth", "4", "--dominance", "100", "--out", str(out)]
    assert main(args + ["--alias-dominance", "0"]) == 0
    doc = json.loads(out.read_text())
    assert doc["criterion"]["dominance"] == 100 and doc["verdict"] == "stable"
    assert main(args) == 0
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "chatter" and max(sg["n_alias"] for sg in doc["segments"] if sg["kind"] == "cut") >= 1


def test_the_plot_shows_the_spectra_the_verdict_rests_on():
    """The real recording's plot: its segment labels do not print over each other (an entry, two stable windows and
    the chatter within 10 s of a 63 s record did before), and its second panel holds the chattering cut's and the air
    cut's mean spectra with the chatter frequency marked where `cut` found it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from toolpoint.shop import plot_cut

    rec = real_record()
    res = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=2, full_scale=rec.full_scale)
    fig = plot_cut(res, name=REAL.name)
    FigureCanvasAgg(fig).draw()
    ax, ax2 = fig.axes[:2]
    assert fig._suptitle.get_text().startswith(f"{REAL.name}: chatter at {res.chatter_hz:.1f} Hz; Harmonizer speed")
    labels = [tx for tx in ax.texts if tx.get_text() in ("air", "entry", "exit", "stable", "chatter")]
    assert len(labels) == len(res.segments) >= 6
    boxes = [tx.get_window_extent() for tx in labels]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
    lines = {ln.get_label(): ln for ln in ax2.get_lines()}
    assert {"air cut", "chattering cut", f"chatter {res.chatter_hz:.1f} Hz"} <= set(lines)
    f, db = lines["chattering cut"].get_data()
    f_air, db_air = lines["air cut"].get_data()
    near = np.abs(f - res.chatter_hz) <= 3.0
    assert db[near].max() - db_air[near].max() > 20  # the chatter line stands where the air holds none


def test_a_weak_line_is_chatter_with_its_tooth_passing_aliases_not_alone():
    """A line at 1 % of the strongest harmonic's power that appears with the cut: with its aliases f ± f_t it is
    regenerative chatter; alone (a feed drive, a pump switched on with the cut) it is not."""
    rpm, teeth = 6000.0, 4
    x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=1234.0, chatter_amp=0.1, seed=5)
    r = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
    cut = [sg for sg in r.segments if sg.kind == "cut"]
    assert r.verdict == "chatter" and abs(r.chatter_hz / 1234 - 1) < 0.01
    assert all(0.005 <= sg.dominance < 0.05 and sg.n_alias >= 1 for sg in cut)  # weak, but a family
    # without an air cut "new" cannot be told, nor the cut's own on/off sidebands: the alias rule is off
    x0, rate0, *_ = shop_record(rpm=rpm, teeth=teeth, chatter_hz=1234.0, chatter_amp=0.1, seed=5, air_s=0.0, fans=())
    r0 = analyse_cut(x0, rate0, rpm=rpm, teeth=teeth, full_scale=1.0)
    assert r0.verdict == "stable" and all(sg.n_alias == 0 for sg in r0.segments)
    x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, seed=5)
    t = np.arange(x.size) / rate
    ramp = np.clip((t - t0) / 0.05, 0, 1) * np.clip((t1 - t) / 0.05, 0, 1)
    x = x + 0.025 * ramp * np.sin(2 * np.pi * 1234.0 * t)  # a line alone, about 1 % of the harmonic in power
    r = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
    cut = [sg for sg in r.segments if sg.kind == "cut"]
    assert r.verdict == "stable", [(sg.peak_hz, sg.dominance, sg.n_alias) for sg in cut]
    assert any(abs(sg.peak_hz / 1234 - 1) < 0.01 and sg.dominance >= 0.005 and sg.n_alias == 0 for sg in cut)


def test_a_family_a_few_thousandths_of_the_harmonic_is_chatter_a_weaker_one_is_not():
    """A lightly damped mode at a pocket: the chatter saturates 25 dB under the resonant harmonic, a family
    f_c + j f_t. At 0.0034 of the harmonic's power with its aliases it is chatter (the old default, 0.005, missed
    it); at 0.0015 — the strongest family of any stable simulated record is 0.0013 (docs/design/shop.md) — not."""
    rpm, teeth = 6000.0, 4
    for amp, want in ((0.06, "chatter"), (0.04, "stable")):
        x, rate, *_ = shop_record(rpm=rpm, teeth=teeth, chatter_hz=1234.0, chatter_amp=amp, seed=6)
        r = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
        cut = [sg for sg in r.segments if sg.kind == "cut"]
        assert r.verdict == want, [(sg.peak_hz, sg.dominance, sg.n_alias) for sg in cut]
        assert all(abs(sg.peak_hz / 1234 - 1) < 0.01 and sg.n_alias >= 1 for sg in cut)
        assert all(0.002 * (amp > 0.05) <= sg.dominance < (0.005 if amp > 0.05 else 0.002) for sg in cut)
        assert analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0, alias_dominance=0.005).verdict == "stable"
    assert analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0, alias_dominance=0.0005).verdict == "chatter"


def _write_wav(path, x, rate=44100):
    import soundfile as sf

    sf.write(path, x, rate, subtype="FLOAT")
    return path


@pytest.mark.parametrize("case,field", [
    ("silent", "samples"), ("clipped", "samples"), ("short", "samples"), ("rpm", "--rpm"), ("teeth", "teeth"),
    ("teeth_word", "--teeth"), ("rpm_huge", "rpm"), ("dominance", "--dominance"),
    ("growth", "--growth-db")])
def test_bad_input_is_one_line_exit_2(case, field, tmp_path, capsys):
    x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=0.3, cut_s=0.6, seed=5)
    args = ["--rpm", "6000", "--teeth", "4"]
    if case == "silent":
        x = np.zeros_like(x)
    elif case == "clipped":
        x = np.clip(3 * x, -1, 1)
    elif case == "short":
        x = x[:int(0.05 * rate)]  # 5 revolutions
    elif case == "rpm":
        args = ["--rpm", "-6000", "--teeth", "4"]
    elif case == "teeth":
        args = ["--rpm", "6000", "--teeth", "0"]
    elif case == "teeth_word":
        args = ["--rpm", "6000", "--teeth", "four"]
    elif case == "rpm_huge":
        args = ["--rpm", "6e6", "--teeth", "4"]
    elif case == "dominance":
        args = ["--rpm", "6000", "--teeth", "4", "--dominance", "nan"]
    elif case == "growth":
        args = ["--rpm", "6000", "--teeth", "4", "--growth-db", "-3"]
    wav = _write_wav(tmp_path / "r.wav", x)
    out = tmp_path / "o.json"
    assert main(["cut", str(wav), *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err and "Traceback" not in err
    assert not out.exists()


def _housing_slot_record(rpm, seed, chip_noise):
    """An accelerometer on the housing of an ideal slot with 4 teeth (a constant force: no tooth passing at all;
    tests/milling_sim.py), 1 s of cut between air cuts at 25.6 kS/s: (samples m/s², rate Hz)."""
    from milling_sim import accelerometer

    rate = 25600.0
    t = np.arange(int(1.0 * rate)) / rate
    z = np.zeros_like(t)
    x, rate, *_ = accelerometer((t, z, z, z - 300.0, z + 120.0), rpm=rpm, teeth=4, seed=seed, chip_noise=chip_noise)
    return x, rate


@pytest.mark.parametrize("rpm", [pytest.param(5850.0, marks=pytest.mark.slow), 6800.0,
                                 pytest.param(7150.0, marks=pytest.mark.slow)])  # the fast tier: one speed
def test_a_nominal_speed_several_percent_off_is_warned_with_the_speed_in_the_record(rpm):
    """A nominal speed off by more than the search range (an override, another program's speed) leaves the
    tooth-passing harmonics outside their masks, where they can be judged as chatter. The real recording's spindle
    ran at 6460 rpm: given 5850, 6800 or 7150 rpm (−9 % … +11 %), its tooth-passing harmonics stand out there and
    not within ±3 % of the nominal, and `cut` says so: a warning (heavy chatter can make a comb elsewhere), or at
    6800 rpm, where no comb stands out within the range and no chatter line ≥ 20 dB out at the nominal speed, a
    refusal naming rpm and the speed; at 6500 rpm it does not."""
    rec = real_record()
    try:
        res = analyse_cut(rec.samples, rec.rate_hz, rpm=rpm, teeth=2, full_scale=rec.full_scale)
    except InputError as exc:  # no comb within the range, and no chatter line ≥ 20 dB out at the nominal speed
        assert rpm == 6800.0 and exc.field == "rpm" and "give the speed the spindle ran at" in str(exc)
        assert abs(float(str(exc).split(" dB over the floor at ")[1].split(" rpm")[0]) / 6460.0 - 1) < 0.002
        return
    assert abs(res.criterion["speed_elsewhere_rpm"] / 6460.0 - 1) < 0.002
    said = [w for w in res.criterion["warnings"] if "the spindle ran at" in w]
    assert len(said) == 1, res.criterion["warnings"]


def test_a_stable_record_given_a_wrong_speed_is_warned_and_the_right_speed_is_not():
    x, rate, _, _ = shop_record(rpm=6000, teeth=4, chatter_hz=None, mode_hz=1234.0, seed=1)
    right = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    assert right.criterion["speed_elsewhere_rpm"] is None and right.verdict == "stable"
    for nominal in (5600.0, 6300.0):  # −6.7 %, +5 %: warned, or refused where no comb stands out in the range
        try:
            wrong = analyse_cut(x, rate, rpm=nominal, teeth=4, full_scale=1.0)
            named = wrong.criterion["speed_elsewhere_rpm"]
        except InputError as exc:  # a stable cut judged at a speed whose harmonics are not heard: no verdict
            assert exc.field == "rpm" and "the spindle ran at" in str(exc), nominal
            named = float(str(exc).split(" dB over the floor at ")[1].split(" rpm")[0])
        assert abs(named / 6000.0 - 1) < 1e-3, nominal


def test_the_spindle_speed_is_read_from_a_record_with_few_harmonics():
    # such a record holds only the spindle's 1x and 2x lines and the bearings'; the comb over all the harmonics read
    # these records 0.4–1.3 % off (23 of 24 at 12000–30000 rpm), which unmasks the 2x line and can make it "chatter"
    for rpm in (19118.0, 24000.0):
        for seed in range(3):
            x, rate = _housing_slot_record(rpm, seed, 0.005)
            r = analyse_cut(x, rate, rpm=rpm * 1.004, teeth=4)
            assert abs(r.rpm / rpm - 1) < 5e-4, (rpm, seed, r.rpm)
            assert r.verdict == "stable"


@pytest.mark.parametrize("chip_noise,seeds", [
    # the chip formation's force noise (2 % of the mean force) excites the housing's 2.5 kHz mode (ζ 4 %: a 200 Hz wide
    # hump) and the cut has nothing to measure "strong" against: 8 of these 12 were called chatter before the speed
    # was read from the lines, 10 of 12 after it and before the line test (5–6 s: in the slow tier since the fast
    # tier read 177–180 s on 2026-12-01)
    pytest.param(0.02, 6, marks=pytest.mark.slow),
    # without chip noise the housing hears nothing of the slot but the bearings' ball-pass lines, which the cutting
    # load raises by 8 dB: the level does not split air from cut, and the step read as growth on all 6 before the
    # step check
    (0.0, 3)])
def test_a_housing_record_of_a_slot_without_chatter_is_stable(chip_noise, seeds):
    for rpm in (19118.0, 24000.0):
        for seed in range(seeds):
            x, rate = _housing_slot_record(rpm, seed, chip_noise)
            r = analyse_cut(x, rate, rpm=rpm * 1.004, teeth=4)
            assert r.verdict == "stable", (rpm, seed, r.chatter_hz)


def test_the_step_ratio_matches_a_brute_force_fit_and_tells_a_ramp_from_a_step():
    from toolpoint.shop.detect import _STEP_RATIO, _step_ratio

    rng = np.random.default_rng(0)
    n = 30
    ramp = np.linspace(0, 10, n) + rng.normal(0, 0.5, n)  # chatter growing: a ramp in dB
    step = np.where(np.arange(n) < 12, 0.0, 8.0) + rng.normal(0, 0.5, n)  # a line jumping with the load
    for y, want_step in ((ramp, False), (step, True)):
        k = np.arange(n) - 0.5 * (n - 1)
        line = y - y.mean() - (k @ (y - y.mean())) / (k @ k) * k
        best = min(np.sum((y[:m] - y[:m].mean()) ** 2) + np.sum((y[m:] - y[m:].mean()) ** 2) for m in range(2, n - 1))
        r = _step_ratio((10 ** (y / 10))[:, None], slice(0, 1))
        assert r == pytest.approx(best / np.sum(line**2), rel=1e-9)
        assert (r < _STEP_RATIO) == want_step


def test_a_record_with_a_non_finite_sample_is_refused_through_the_api():
    # the file readers refuse it; a notebook's array reaches analyse_cut directly (it was judged "stable" before)
    x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=0.3, cut_s=0.6, seed=5)
    x[5000] = np.nan
    with pytest.raises(InputError, match="sample 5000") as e:
        analyse_cut(x, rate, rpm=6000, teeth=4, source="rec")
    assert e.value.field == "samples"


def test_a_stereo_array_is_refused_through_the_api_not_read_as_samples():
    # soundfile.read gives a stereo file as (T, 2); passed on as read it reached the splitting as a 2-D array and
    # raised a NumPy broadcasting error (2026-12-04)
    x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=0.3, cut_s=0.6, seed=5)
    with pytest.raises(InputError, match=r"one channel, shape \(T,\); got shape \(\d+, 2\)") as e:
        analyse_cut(np.stack([x, x], axis=1), rate, rpm=6000, teeth=4, source="rec.wav")
    assert e.value.field == "samples"
    assert analyse_cut(x, rate, rpm=6000, teeth=4).verdict in ("stable", "chatter")


def test_records_one_column_needs_rate_and_uff58(tmp_path):
    import pyuff

    rate = 20000.0
    x, _, *_ = shop_record(rpm=6000, teeth=4, rate=rate, air_s=0.2, cut_s=0.5, seed=6)
    col = tmp_path / "acc.txt"
    np.savetxt(col, x)
    with pytest.raises(InputError, match="rate_hz"):
        read_cut_record(col)
    r = read_cut_record(col, rate_hz=rate)
    assert r.rate_hz == rate and r.samples.size == x.size
    uff = tmp_path / "acc.uff"
    ds = pyuff.prepare_58(func_type=1, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, data=x,
                          x=np.arange(x.size) / rate, id1="acc", ord_data_type=4, abscissa_spacing=1,
                          abscissa_spec_data_type=17, ordinate_spec_data_type=12, orddenom_spec_data_type=0, binary=0)
    pyuff.UFF(str(uff)).write_sets([ds], mode="overwrite")
    r = read_cut_record(uff)
    assert abs(r.rate_hz - rate) < 1e-6 * rate
    np.testing.assert_allclose(r.samples, x, rtol=1e-6, atol=1e-9)
    two = tmp_path / "two.csv"
    np.savetxt(two, np.c_[np.arange(x.size) / rate, x, -x], delimiter=",")
    with pytest.raises(InputError, match="channel"):
        read_cut_record(two)
    assert read_cut_record(two, channel=1).samples[5] == pytest.approx(-x[5])
    # a spreadsheet's export in a decimal-comma locale: cells split at ';', "0,25" is 0.25
    sheet = tmp_path / "sheet.csv"
    sheet.write_text("Zeit [s];Beschleunigung [m/s²]\n" + "".join(
        f"{k / rate:.9f};{v:.9g}\n".replace(".", ",") for k, v in enumerate(x)), encoding="utf-8")
    r = read_cut_record(sheet)
    assert abs(r.rate_hz - rate) < 1e-6 * rate
    np.testing.assert_allclose(r.samples, x, rtol=1e-6, atol=1e-9)


def test_a_weak_growing_line_is_chatter_a_steady_or_decaying_one_is_not():
    """Instability is growth: a lone line under the tooth-passing harmonic (< 5 % of its power, no alias)
    that grows 20 dB over the cut is chatter barely past the limit; the same line steady (a tone switched on
    with the cut) or decaying (the entry's free vibration) is not."""
    rpm, teeth = 6000.0, 4
    x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, seed=5)
    t = np.arange(x.size) / rate
    ramp = np.clip((t - t0) / 0.05, 0, 1) * np.clip((t1 - t) / 0.05, 0, 1)
    rise = 10 ** ((t - t0) / (t1 - t0))  # × 10 in amplitude over the cut: 20 dB
    line = np.sin(2 * np.pi * 1234.0 * t)
    for amp, want in ((0.01 * rise, "chatter"), (0.03, "stable"), (0.1 / rise, "stable")):
        r = analyse_cut(x + amp * ramp * line, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
        cut = [sg for sg in r.segments if sg.kind == "cut"]
        assert r.verdict == want, [(sg.peak_hz, sg.dominance, sg.growth_db) for sg in cut]
        assert all(sg.dominance < 0.05 and sg.n_alias == 0 for sg in cut)  # neither ratio would call it
        if want == "chatter":
            assert abs(r.chatter_hz / 1234 - 1) < 0.01 and all(sg.growth_db >= 6 for sg in cut)
            # without the growth test it is missed
            assert analyse_cut(x + amp * ramp * line, rate, rpm=rpm, teeth=teeth, full_scale=1.0,
                               growth_db=0).verdict == "stable"


@pytest.mark.slow  # 7–9 s: the fast tier read 177 s on the shared VM (limit 3 min)
def test_a_drooping_or_wandering_spindle_is_not_chatter():
    # The spindle's speed wanders (±0.3 % at 0.5 Hz) or droops when the tool enters (1 %, half recovered by the
    # drive); its harmonics move with it. A mask fixed at one speed leaves their moving flanks as new lines near
    # them. A step of the override in the middle of the cut (1.5 %) too. With the speed untracked, 3 of the 9 wander
    # records below and the step record were called chatter (and 12 of 12 stable records with steps of 0.5–3 % from
    # a second generator: docs/design/shop.md). Tracked from the lowest tooth-passing harmonics, each judged part
    # masks the speeds it ran at.
    false = []
    cases = [(0.0, 0.003, 0.0, seed) for seed in range(3)] + [(0.01, 0.0, 0.0, 3), (0.0, 0.0, 0.015, 4)]
    for droop, wander, step, seed in cases:
        for rpm, teeth in ((6000, 4), (12000, 2), (9000, 3))[: 3 if wander else 1]:
            x, rate, *_ = shop_record(rpm=rpm, teeth=teeth, speed_droop=droop, speed_wander=wander, speed_step=step,
                                      seed=seed)
            res = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
            assert res.criterion["speed_tracked"] and res.criterion["speed_wander"] < 2 * max(droop, wander, step)
            assert abs(res.rpm / rpm - 1) < 0.02
            false += [(droop, wander, step, seed, rpm)] if res.verdict != "stable" else []
    assert not false
    # chatter is still found, at its frequency
    for step in (0.0, 0.015):
        x, rate, *_ = shop_record(rpm=9000, teeth=3, chatter_hz=1234.0, chatter_amp=0.5, speed_droop=0.005,
                                  speed_wander=0.003, speed_step=step, seed=9)
        res = analyse_cut(x, rate, rpm=9000, teeth=3, full_scale=1.0)
        assert res.verdict == "chatter" and abs(res.chatter_hz / 1234.0 - 1) < 0.01
    # a steady spindle is not tracked: the mask of the steady speed, as before
    x, rate, *_ = shop_record(rpm=6000, teeth=4, seed=1)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    assert not res.criterion["speed_tracked"] and res.criterion["speed_wander"] < 5e-4


@pytest.mark.parametrize("attack_s,release_s", [(0.05, 2.0), pytest.param(0.5, 0.5, marks=pytest.mark.slow)])
def test_a_record_levelled_by_automatic_gain_control_is_split_and_judged_right(attack_s, release_s):
    # A phone levels the cut to the air cut's loudness within its attack time and lifts the air after the cut back
    # within its release time, so the band's power no longer tells air from cut: the air before the cut sounded as
    # loud as the cut, and split by level it was judged as cutting (false chatter in 3 of these 6 stable records
    # before, and the cut's bounds wrong in 6 of the 12). The tooth-passing harmonics' prominence within each frame
    # does not move with the gain.
    for rpm, teeth, fc, seed in ((6000, 4, 1234.0, 0), (9000, 3, 1630.0, 1), (12000, 2, 2890.0, 2)):
        for chatter in (None, fc):
            x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=chatter, chatter_amp=0.5, mode_hz=fc,
                                          cut_s=4.0, seed=seed)
            res = analyse_cut(phone_agc(x, rate, attack_s, release_s), rate, rpm=rpm, teeth=teeth, full_scale=1.0)
            assert res.verdict == ("stable" if chatter is None else "chatter"), (rpm, chatter)
            if chatter is not None:
                assert abs(res.chatter_hz / fc - 1) < 0.01
            cut = [s for s in res.segments if s.kind != "air"]
            assert abs(cut[0].start_s - t0) < 0.2 and abs(cut[-1].end_s - t1) < 0.2


def test_a_loud_noise_through_air_cut_and_cut_does_not_hide_the_air_cut():
    # Flood coolant (broadband 300 Hz–8 kHz, as loud as the record: it runs before the tool enters) leaves the cut
    # under 4 dB louder than the air, so no level splits the record; judged as one cut without an air cut, the
    # fans became chatter in all 9 stable records of this kind over 3 seeds before (docs/design/shop.md). The
    # tooth-passing harmonics, read in the long frames, still stand out in the cut only.
    from scipy import signal

    for rpm, teeth, fc, seed in ((6000, 4, 1234.0, 0), (9000, 3, 1630.0, 1), (12000, 2, 2890.0, 2)):
        for chatter in (None, fc):
            x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=chatter, chatter_amp=0.5, mode_hz=fc,
                                          cut_s=3.0, seed=seed)
            b, a = signal.butter(2, [300, 8000], btype="band", fs=rate)
            noise = signal.lfilter(b, a, np.random.default_rng(seed + 100).standard_normal(x.size))
            y = x + np.std(x) * noise / np.std(noise)
            res = analyse_cut(0.9 * y / np.abs(y).max(), rate, rpm=rpm, teeth=teeth, full_scale=1.0)
            assert res.verdict == ("stable" if chatter is None else "chatter"), (rpm, chatter)
            cut = [s for s in res.segments if s.kind != "air"]
            assert res.segments[0].kind == "air" and res.segments[-1].kind == "air"
            assert abs(cut[0].start_s - t0) < 0.25 and abs(cut[-1].end_s - t1) < 0.25


def test_chatter_on_a_mains_harmonic_without_an_air_cut_is_flagged():
    # Hum from a ground loop (50 Hz and its odd harmonics, 10 dB under the record's RMS) is a steady tone: with an
    # air cut it is there before the cut and is not a candidate; without one only its strength is judged, and
    # 2 of 6 such stable records are called chatter at 50.0 Hz. The verdict says what it cannot rule out.
    def hummed(air_s, chatter_hz=None):
        x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=air_s, fans=(), chatter_hz=chatter_hz, chatter_amp=0.5,
                                  seed=0)
        t = np.arange(x.size) / rate
        a = np.std(x) * 10 ** (-10 / 20)
        x = x + sum(a / k * np.sin(2 * np.pi * 50 * k * t + k) for k in (1, 3, 5, 7))
        return analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=None)

    res = hummed(0.0)
    assert res.verdict == "chatter" and abs(res.chatter_hz - 50.0) < 0.5
    assert len(res.criterion["warnings"]) == 1 and "mains harmonic 1 x 50 Hz" in res.criterion["warnings"][0]
    res = hummed(1.0)
    assert res.verdict == "stable" and res.criterion["warnings"] == []
    res = hummed(0.0, chatter_hz=1234.0)  # chatter off the mains harmonics: no mains warning
    assert res.verdict == "chatter" and abs(res.chatter_hz / 1234.0 - 1) < 0.01
    assert not any("mains" in w for w in res.criterion["warnings"])
    # but a steady line (this synthetic chatter is developed from the start) without an air cut is what a tone of the
    # machine's own would look like: said (test_the_real_spindle_in_air_alone_is_not_chatter_said_without_a_doubt)
    assert len(res.criterion["warnings"]) == 1 and "steady line" in res.criterion["warnings"][0]


def test_the_spectra_computed_in_chunks_are_those_of_all_frames_at_once():
    """The frames are windowed and transformed a chunk at a time (10 min of audio held 3.8 GB at once): the same
    power spectra as the textbook all-frames computation, to rounding."""
    from toolpoint.shop.detect import _stft

    x = np.random.default_rng(3).standard_normal(20_011)
    L, hop = 512, 128
    n = 1 + (x.size - L) // hop
    w = np.hanning(L)
    frames = x[np.arange(L)[None, :] + hop * np.arange(n)[:, None]]
    direct = np.abs(np.fft.rfft(frames * w, axis=1)) ** 2 / np.sum(w * w)
    for chunk in (L, 5 * L + 7, 1 << 21):
        p, centres = _stft(x, L, hop, chunk=chunk)
        np.testing.assert_allclose(p, direct, rtol=1e-12, atol=1e-12 * direct.max())
        np.testing.assert_array_equal(centres, np.arange(n) * hop + L / 2)


def test_the_mean_of_chosen_frames_is_numpys_own_bit_for_bit():
    """The mean spectrum of a run of frames is summed a chunk at a time instead of from a copy of the rows (a long
    record's air cut held a fifth of its peak memory in one): NumPy's ``P[sel].mean(axis=0)`` exactly, for masks and
    for index lists with repeats (frames that two runs share are counted twice, as before)."""
    from toolpoint.shop.detect import _rows_mean

    rng = np.random.default_rng(5)
    P = rng.random((3000, 257)) ** 6 * 1e4
    mask = rng.random(3000) < 0.7
    idx = np.sort(rng.choice(3000, 2500, replace=True))
    for sel in (mask, idx, idx[:40], np.flatnonzero(mask)):
        np.testing.assert_array_equal(_rows_mean(P, sel, chunk=512), P[sel].mean(axis=0))


def test_the_air_beside_the_harmonics_is_read_at_its_own_level():
    """The long frame beside the harmonics compares a cut's line with the air cut's level there. The air's frame was
    windowed whole and then cropped by the FFT to four times the cut's samples, part of a Hann window scaled as the
    whole one: after 8 s of air (the most it takes) the air's level 3.0 dB low under a 1 s cut, 14 dB under a 0.5 s
    one (the shortest it reads), so a line of the cut rose over the air by that much more (the code before
    2026-12-06). White noise of one level in both: the same density to 0.5 dB (the medians of ≥ 2 000 periodogram
    bins); a tone of one amplitude 4 × the cut's peak (the air's frame 4 × as long)."""
    from toolpoint.shop.detect import _long_psd

    rate = 44100.0
    rng = np.random.default_rng(7)
    for cut_s, air_s in ((0.5, 8.0), (1.0, 8.0), (3.0, 8.0), (2.0, 1.5)):
        n = int(cut_s * rate)
        f, p = _long_psd(rng.standard_normal(n), rate, n)
        fa, pa = _long_psd(rng.standard_normal(int(air_s * rate)), rate, min(n, int(air_s * rate)))
        band, band_a = (f > 500) & (f < 5000), (fa > 500) & (fa < 5000)
        gap_db = 10 * np.log10(np.median(pa[band_a]) / np.median(p[band]))
        assert abs(gap_db) < 0.5, (cut_s, air_s, gap_db)
    # a noise-free tone: its density's peak grows with the frame, so the air's frame is the cut's length at most 4×
    t = np.arange(int(8.0 * rate)) / rate
    tone = np.sin(2 * np.pi * 1234.5 * t)
    n = int(1.0 * rate)
    _, p = _long_psd(tone[:n], rate, n)
    _, pa = _long_psd(tone, rate, n)
    assert 10 * np.log10(pa.max() / p.max()) == pytest.approx(10 * np.log10(4.0), abs=0.5)


@pytest.mark.slow
def test_a_long_record_s_analysis_holds_a_few_copies_of_it():
    """Memory of a long record (the real recording four times over, 4.2 min): the analysis's own allocations at
    their peak, as tracemalloc counts NumPy's, are at most 3.5 times the record's float64 samples — 3.1× measured,
    6.2× before the spectra were kept only up to the band and the means taken without copies (2026-12-06:
    ``docs/design/shop.md``, *A long record's memory*)."""
    import tracemalloc

    rec = real_record()
    x = np.tile(rec.samples, 4)
    tracemalloc.start()
    try:
        res = analyse_cut(x, rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1067.3, rel=2e-3)
    assert peak <= 3.5 * x.nbytes, (peak / 1e6, x.nbytes / 1e6)


def test_running_out_of_memory_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    """A record too long for the machine's memory (a whole session's recording): one line saying so and what to make
    smaller, exit 2, no traceback, no output file."""
    import soundfile as sf

    import toolpoint.shop as shop

    x, rate, *_ = shop_record(rpm=6000, teeth=4, seed=1)
    rec = tmp_path / "r.wav"  # as audio: a CSV of the 4 s took 2 s to write and read, and the read is not the subject
    sf.write(rec, 0.5 * x / np.abs(x).max(), int(rate), subtype="FLOAT")

    def too_big(*a, **k):
        raise MemoryError("Unable to allocate 91.0 MiB for an array with shape (24009, 497) and data type float64")

    monkeypatch.setattr(shop, "analyse_cut", too_big)
    out = tmp_path / "cut.json"
    assert main(["cut", str(rec), "--rpm", "6000", "--teeth", "4", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "not enough memory" in err and "shorter record" in err
    assert not out.exists()


def test_audio_in_the_containers_recorders_write_is_read(tmp_path):
    """What libsndfile reads is read, by suffix or by first bytes: Apple's CAF (a Mac's or an iPhone app's recorder),
    RF64 and Wave64 (a field recorder's or a DAQ's WAV past 4 GB), AU, Ogg Opus. CAF and Wave64 were refused as
    "not a UTF-8 text file"."""
    import shutil

    import soundfile as sf

    x, rate, *_ = shop_record(rpm=6000, teeth=4, seed=2, rate=48000.0)
    y = (0.5 * x / np.abs(x).max()).astype(np.float32)
    for name, fmt, sub in (("a.caf", "CAF", "PCM_16"), ("a.rf64", "RF64", "PCM_24"), ("a.w64", "W64", "FLOAT"),
                           ("a.au", "AU", "PCM_16"), ("a.opus", "OGG", "OPUS")):
        try:
            sf.write(tmp_path / name, y, int(rate), format=fmt, subtype=sub)
        except (sf.LibsndfileError, ValueError, TypeError):
            if sub == "OPUS":  # an older libsndfile without Opus; every other container must be written and read
                continue
            raise
        shutil.copy(tmp_path / name, tmp_path / f"copy_{fmt}")  # and without its suffix
        for path in (tmp_path / name, tmp_path / f"copy_{fmt}"):
            r = read_cut_record(path)
            assert r.rate_hz == rate and r.samples.size == y.size, name
            if sub != "OPUS":  # lossless: the samples themselves
                assert np.allclose(r.samples, y, atol=1e-4), name


def test_a_record_is_known_by_its_first_bytes(tmp_path, capsys):
    """A WAV renamed .csv or without a suffix is read as audio; a MATLAB .mat file (or HDF5, TDMS) is refused with one
    line that says how to export the signal, not as 'not a UTF-8 text file'."""
    import shutil

    import scipy.io
    import soundfile as sf

    x, rate, *_ = shop_record(rpm=6000, teeth=4, seed=2)
    wav = tmp_path / "cut.wav"
    sf.write(wav, x / np.abs(x).max() * 0.5, int(rate), subtype="PCM_24")
    ref = read_cut_record(wav)
    for name in ("cut.csv", "cut"):
        shutil.copy(wav, tmp_path / name)
        r = read_cut_record(tmp_path / name)
        assert r.rate_hz == ref.rate_hz and np.array_equal(r.samples, ref.samples)
    # a spreadsheet's "Unicode text": UTF-16 (its byte-order mark FF FE is no MP3 frame), tab-separated, here with the
    # decimal comma of a German locale
    u16 = tmp_path / "cut.txt"
    u16.write_text("Zeit (s)\tp\n" + "".join(f"{k / rate:.7f}\t{v:.7g}\n".replace(".", ",")
                                             for k, v in enumerate(x[:4410])), encoding="utf-16")
    r = read_cut_record(u16)
    assert abs(r.rate_hz / rate - 1) < 1e-6 and np.allclose(r.samples, x[:4410], rtol=1e-6, atol=1e-9)
    mat = tmp_path / "cut.mat"
    scipy.io.savemat(mat, {"acc": x, "fs": rate})
    with pytest.raises(InputError, match="MATLAB .mat file.*audiowrite"):
        read_cut_record(mat)
    assert main(["cut", str(mat), "--rpm", "6000", "--teeth", "4"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cut.mat" in err
    # what phones record, which libsndfile does not read: it was "no data rows" (read as a text table) or "not a
    # UTF-8 text file"; now the format and how to convert it, by the first bytes (an ISO-media box 'ftyp', an ADTS
    # frame, AMR's magic) whatever the suffix
    heads = {"memo.m4a": b"\x00\x00\x00\x1cftypM4A \x00\x00\x00\x00M4A isommp42",
             "memo": b"\x00\x00\x00\x18ftyp3gp4\x00\x00\x00\x00isom", "memo.aac": b"\xff\xf1\x50\x80\x2f\xdf\xfc",
             "memo.amr": b"#!AMR\n\x3c"}
    for name, head in heads.items():
        f = tmp_path / name
        f.write_bytes(head + bytes(4000))
        assert main(["cut", str(f), "--rpm", "6000", "--teeth", "4"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and name in err and f"ffmpeg -i {name} {f.stem}.wav" in err, err


@pytest.mark.parametrize("start_s,end_s", [(0.0, 6.5), (20.0, 40.0)])
def test_the_real_spindle_in_air_alone_is_not_chatter_said_without_a_doubt(start_s, end_s):
    """The real recording's spindle running in air, before and after the cut, cut out as a record of its own: no air
    cut to compare with, and the machine's own lines (1770.7 Hz, 2329.9 Hz) stand out of the floor like chatter. A
    steady line without an air cut is chatter by its strength alone: if called chatter, `cut` says so."""
    rec = real_record()
    a, b = int(start_s * rec.rate_hz), int(end_s * rec.rate_hz)
    res = analyse_cut(rec.samples[a:b], rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert all(s.kind != "air" for s in res.segments)  # nothing to compare with
    if res.verdict == "chatter":
        assert any("steady line" in w and "no air cut" in w for w in res.criterion["warnings"])
    # the cut itself, cut out without its air: chatter that grows, not warned of
    a, b = int(7.2 * rec.rate_hz), int(16.0 * rec.rate_hz)
    cut = analyse_cut(rec.samples[a:b], rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert cut.verdict == "chatter" and not any("steady line" in w for w in cut.criterion["warnings"])


def test_a_daq_s_time_column_printed_to_its_digits_and_in_ms(tmp_path):
    """A DAQ's CSV at 25.6 kHz with the time printed to 1 µs has steps of 39 and 40 µs: read, at the rate of the first
    and last rows; the same in ms under a "Time (ms)" header; a missing sample, a time printed with too few digits
    to increase, are refused naming the line."""
    rate = 25600.0
    t = 12.345 + np.arange(int(0.5 * rate)) / rate
    x = np.sin(2 * np.pi * 400 * t)
    us = tmp_path / "daq.csv"
    np.savetxt(us, np.c_[t, x], delimiter=",", fmt=["%.6f", "%.6g"], header="Time (s),Accel (g)", comments="")
    assert read_cut_record(us).rate_hz == pytest.approx(rate, rel=1e-6)
    ms = tmp_path / "daq_ms.csv"
    np.savetxt(ms, np.c_[1e3 * t, x], delimiter=",", fmt=["%.3f", "%.6g"], header="Time (ms),Accel (g)", comments="")
    r = read_cut_record(ms)
    assert r.rate_hz == pytest.approx(rate, rel=1e-6) and r.samples.size == t.size
    gap = tmp_path / "gap.csv"
    np.savetxt(gap, np.delete(np.c_[t, x], 5000, axis=0), delimiter=",", fmt=["%.6f", "%.6g"], header="t,a",
               comments="")
    with pytest.raises(InputError, match=r"line 5002: a time step of 7\.[89]e-05 s where the steps are 3\.9e-05 s"):
        read_cut_record(gap)
    coarse = tmp_path / "coarse.csv"
    np.savetxt(coarse, np.c_[t, x], delimiter=",", fmt=["%.4f", "%.6g"], header="t,a", comments="")
    with pytest.raises(InputError, match="line 3: the time .* does not increase: printed with too few digits"):
        read_cut_record(coarse)


def test_a_daq_s_export_with_a_comment_column_and_a_units_row(tmp_path):
    """Two exports a shop's DAQ writes as they are: a LabVIEW measurement file (a header block, then
    ``X_Value,Accel_X (g),Accel_Y (g),Comment`` with the Comment column empty on every row) and a Dewesoft-like
    CSV (``Time;AI 1;AI 2`` over a units row ``ms;g;g``, decimal commas). The empty column is no channel (it was
    "column 3: '' is not a number"), the time unit is read from the units row (ms: the rate was 1000 × off), and
    the channels are named by the header, in the refusal that asks for one and in the record."""
    rate = 25600.0
    t = np.arange(int(0.5 * rate)) / rate
    x = np.sin(2 * np.pi * 400 * t)
    lvm = tmp_path / "run.csv"
    lvm.write_text("LabVIEW Measurement\nWriter_Version,2\nSeparator,Comma\n***End_of_Header***\n"
                   "X_Value,Accel_X (g),Accel_Y (g),Comment\n"
                   + "".join(f"{a:.8f},{b:.6e},{0.5 * b:.6e},\n" for a, b in zip(t, x)))
    with pytest.raises(InputError, match=r"run.csv: channel: 2 signal columns: choose one with --channel "
                                         r"\(0: Accel_X \(g\), 1: Accel_Y \(g\)\)"):
        read_cut_record(lvm)
    r = read_cut_record(lvm, channel=1)
    assert r.rate_hz == pytest.approx(rate, rel=1e-6) and r.channel == "1 (Accel_Y (g))"
    assert np.allclose(r.samples, 0.5 * x, atol=1e-6)
    dw = tmp_path / "dewe.csv"
    dw.write_text("Time;AI 1;AI 2\nms;g;g\n" + "".join(f"{1e3 * a:.5f};{b:.6e};{-b:.6e}\n".replace(".", ",")
                                                        for a, b in zip(t, x)))
    r = read_cut_record(dw, channel=0)
    assert r.rate_hz == pytest.approx(rate, rel=1e-6) and r.channel == "0 (AI 1 (g))"
    assert np.allclose(r.samples, x, atol=1e-6)
    blank = tmp_path / "blank.csv"  # a cell empty in some rows only is a missing sample, still refused
    blank.write_text("t,a,b\n0,1,2\n0.001,,2\n0.002,1,\n")
    with pytest.raises(InputError, match=r"blank.csv: column 1: line 3: '' is not a number"):
        read_cut_record(blank)


@pytest.mark.slow  # 6–7 s: the fast tier read 177–180 s on the shared VM on 2026-12-01 (limit 3 min)
def test_a_record_of_cuts_at_two_speeds_is_refused_and_judged_in_parts(tmp_path, capsys):
    """One --rpm judges one speed. Two test cuts recorded in one file at 6000 and 8000 rpm: given 6000 rpm the
    8000 rpm cut's tooth passing was "chatter at 533.4 Hz", given 8000 rpm the 6000 rpm cut's spindle line
    "chatter at 100.0 Hz". Now refused naming the cut and its speed, and each part judged alone (``span_s``,
    ``--start``/``--end``). The same on the real recording followed by itself played 1.25 × faster (a second cut
    at 8075 rpm): refused both ways, each part judged as the recording is. Two cuts at one speed are judged."""
    import soundfile as sf
    from scipy.signal import resample_poly

    a, rate, *_ = shop_record(rpm=6000, teeth=4, seed=1)
    b, _, *_ = shop_record(rpm=8000, teeth=4, seed=3, chatter_hz=1234.0, chatter_amp=0.5)
    c, _, *_ = shop_record(rpm=6000, teeth=4, seed=2, chatter_hz=1234.0, chatter_amp=0.5)
    x = np.concatenate([a, b])
    with pytest.raises(InputError, match=r"rpm: the cut at 5\.0–7\.0 s ran at another spindle speed, ≈ 8000 rpm.*"
                                         r"--start/--end \(that cut with its air: 4\.0–7\.5 s\)"):
        analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    with pytest.raises(InputError, match=r"rpm: the cut at 1\.0–3\.0 s ran at another spindle speed, ≈ 600[01] rpm"):
        analyse_cut(x, rate, rpm=8000, teeth=4, full_scale=1.0)
    assert analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0, span_s=(0, 4)).verdict == "stable"
    r = analyse_cut(x, rate, rpm=8000, teeth=4, full_scale=1.0, span_s=(4, np.inf))
    assert r.verdict == "chatter" and abs(r.chatter_hz / 1234 - 1) < 0.01 and r.criterion["span_s"] == [4, 8]
    assert min(g.start_s for g in r.segments) == pytest.approx(4.0) and r.time_s[0] > 4
    same = analyse_cut(np.concatenate([a, c]), rate, rpm=6000, teeth=4, full_scale=1.0)
    assert [g.verdict for g in same.segments if g.kind == "cut"] == ["stable", "chatter"]
    assert [(round(t0), round(t1), v) for t0, t1, v, _ in same.cuts] == [(1, 3, "stable"), (5, 7, "chatter")]
    assert same.cuts[1][3] == pytest.approx(1234.0, rel=0.01) and len(same.to_dict()["cuts"]) == 2
    rec = real_record()
    part = rec.samples[:int(25 * rec.rate_hz)]  # air, the cut, air
    both = np.concatenate([part, resample_poly(part, 4, 5)])
    for rpm, where in ((6500, r"30\.\d–3\d\.\d s ran at another spindle speed, ≈ [78]\d\d\d rpm"),
                       (8075, r"6\.\d–16\.\d s ran at another spindle speed, ≈ 64\d\d rpm")):
        with pytest.raises(InputError, match=r"the cut at " + where):
            analyse_cut(both, rec.rate_hz, rpm=rpm, teeth=2, full_scale=1.0)
    r1 = analyse_cut(both, rec.rate_hz, rpm=6500, teeth=2, full_scale=1.0, span_s=(0, 25))
    r2 = analyse_cut(both, rec.rate_hz, rpm=8075, teeth=2, full_scale=1.0, span_s=(25, 50))
    assert r1.chatter_hz == pytest.approx(1067.3, abs=0.2) and r2.chatter_hz == pytest.approx(1.25 * 1067.3, rel=2e-3)
    twice = analyse_cut(np.concatenate([part, part]), rec.rate_hz, rpm=6500, teeth=2, full_scale=1.0)
    assert twice.verdict == "chatter" and twice.chatter_hz == pytest.approx(1067.3, abs=0.2)
    # the command line: --start/--end, and a start past the record's end refused naming --start
    wav = tmp_path / "two.wav"
    sf.write(wav, 0.5 * x / np.abs(x).max(), int(rate), subtype="PCM_16")
    assert main(["cut", str(wav), "--rpm", "6000", "--teeth", "4"]) == 2
    assert "ran at another spindle speed" in capsys.readouterr().err
    sess = tmp_path / "session.wav"  # two cuts at one speed: each cut's verdict on a line of its own
    y = np.concatenate([a, c])
    sf.write(sess, 0.5 * y / np.abs(y).max(), int(rate), subtype="PCM_16")
    assert main(["cut", str(sess), "--rpm", "6000", "--teeth", "4", "--out", str(tmp_path / "s.json")]) == 0
    said = capsys.readouterr().out.splitlines()
    assert said[0].startswith("session.wav: chatter at 123") and said[1].startswith("session.wav: 2 cuts: 1.0–3.0 s "
                                                                                       "stable; 5.0–7.0 s chatter at")
    # … each with the part that holds its air: judged there, a cut keeps its verdict; a part of the cut alone warns
    assert said[1].endswith("(each with its air, to judge alone with --start/--end: 0.5–4.0 s, 4.0–7.5 s)"), said[1]
    assert np.allclose([c["part_s"] for c in json.loads((tmp_path / "s.json").read_text())["cuts"]],
                       [[0.5, 4.0], [4.0, 7.5]], atol=0.02)
    assert analyse_cut(y, rate, rpm=6000, teeth=4, full_scale=1.0, span_s=same.parts[1]).verdict == "chatter"
    alone = analyse_cut(y, rate, rpm=6000, teeth=4, full_scale=1.0, span_s=(5.2, 6.8))
    assert any(w.startswith("the part 5.2–6.8 s holds no air cut") for w in alone.criterion["warnings"])
    assert not any("holds no air cut" in w for w in analyse_cut(y, rate, rpm=6000, teeth=4, full_scale=1.0,
                                                             span_s=same.parts[0]).criterion.get("warnings", ()))
    # … and a test-cut table's row, which is one cut, is warned that its record holds two that disagree
    from toolpoint.shop.update import read_test_cuts

    (tmp_path / "cuts.csv").write_text("rpm,depth_mm,result,record\n6000,0.5,,session.wav\n")
    row = read_test_cuts(tmp_path / "cuts.csv", teeth=4)[0]
    assert not row.stable and any("session.wav: the record holds 2 cuts (1.0–3.0 s stable; 5.0–7.0 s chatter)" in w
                                  for w in row.warnings), row.warnings
    out = tmp_path / "b.json"
    assert main(["cut", str(wav), "--rpm", "8000", "--teeth", "4", "--start", "4", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["verdict"] == "chatter"
    assert main(["cut", str(wav), "--rpm", "8000", "--teeth", "4", "--start", "9"]) == 2
    assert "two.wav: --start: 9 s is after the record's end (8 s)" in capsys.readouterr().err
    # one file named for two outputs: refused before any work (the table replaced the JSON without a word)
    both = tmp_path / "both.csv"
    assert main(["cut", str(sess), "--rpm", "6000", "--teeth", "4", "--out", str(both), "--table", str(both)]) == 2
    assert "--table: --out, --plot and --table must be different files" in capsys.readouterr().err
    assert not both.exists()


def test_a_daq_s_high_rate_is_decimated_to_the_band_judged():
    """A DAQ's 96–192 kHz holds nothing the test looks at above its band (≤ 10 kHz): the record is decimated first
    (2 min at 192 kHz peaked at 2.7 GB before, 0.6 GB after; docs/design/shop.md). The verdict and chatter frequency
    are those of the record at 24 kHz; a band given up to 20 kHz keeps 48 kHz; below 50 kHz nothing is decimated."""
    from scipy.signal import resample_poly

    x, rate, *_ = shop_record(rpm=6000, teeth=4, seed=5, rate=24000.0, chatter_hz=1234.0, chatter_amp=0.5)
    ref = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=None)
    for q in (4, 8):
        r = analyse_cut(resample_poly(x, q, 1), q * rate, rpm=6000, teeth=4, full_scale=None)
        assert r.criterion["analysed_rate_hz"] == 24000.0
        assert r.verdict == ref.verdict == "chatter" and r.chatter_hz == pytest.approx(ref.chatter_hz, abs=0.05)
        assert [g.kind for g in r.segments] == [g.kind for g in ref.segments]
    wide = analyse_cut(resample_poly(x, 4, 1), 96000.0, rpm=6000, teeth=4, full_scale=None, band_hz=(50.0, 20000.0))
    assert wide.criterion["analysed_rate_hz"] == 48000.0 and wide.verdict == "chatter"
    assert analyse_cut(resample_poly(x, 2, 1), 48000.0, rpm=6000, teeth=4).criterion["analysed_rate_hz"] == 48000.0


def test_a_slow_spindle_s_stable_verdict_says_its_masks_cover_the_band():
    """Below ~800 rpm the spindle harmonics lie closer than their masks are wide (±2 bins of a 0.4 s frame): chatter
    there goes unheard (0 of 8 synthetic chattering cuts at 600 rpm), so a 'stable' verdict is warned of; at 3000 rpm
    it is not."""
    for rpm, warned in ((600.0, True), (3000.0, False)):
        for fc in (None, 777.0):
            x, rate, *_ = shop_record(rpm=rpm, teeth=4, chatter_hz=fc, chatter_amp=0.5, seed=0,
                                      air_s=max(1.0, 1500 / rpm), cut_s=max(2.0, 2400 / rpm))
            r = analyse_cut(x, rate, rpm=rpm, teeth=4, full_scale=1.0)
            said = any("their masks cover" in w for w in r.criterion["warnings"])
            if fc is None or not warned:
                assert r.verdict == ("chatter" if fc else "stable") and said == (warned and r.verdict == "stable"), rpm
            else:  # the chatter unheard at 600 rpm: not a silent 'stable'
                assert r.verdict == "chatter" or said


def test_digital_silence_a_dropout_is_refused_and_a_recorder_s_lead_in_is_cut_off(tmp_path, capsys):
    """Runs of one value (zeros, a held sample) are no sound a microphone makes. Inside the real recording (0.3 s of
    zeros at 12 s, a link's dropout) they were the record's quiet level: its air cut became cutting and a machine line
    "chatter at 2329.9 Hz" — refused, naming the time. Before and after the signal (a recorder started early) they are
    cut off: the same verdict, chatter frequency and segments as the recording itself, at the record's own times."""
    import soundfile as sf

    rec = real_record()
    x, rate = rec.samples, rec.rate_hz
    ref = analyse_cut(x, rate, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    drop = x.copy()
    drop[int(12.0 * rate):int(12.3 * rate)] = 0.0
    with pytest.raises(InputError, match=r"a dropout: digital silence for 0.3 s at 12.000–12.300 s"):
        analyse_cut(drop, rate, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    wav = tmp_path / "drop.wav"
    sf.write(wav, drop, int(rate), subtype="FLOAT")
    assert main(["cut", str(wav), "--rpm", "6500", "--teeth", "2", "--out", str(tmp_path / "c.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "drop.wav" in err and "dropout" in err
    assert not (tmp_path / "c.json").exists()
    lead = np.r_[np.zeros(int(0.8 * rate)), x, np.zeros(int(0.5 * rate))]
    res = analyse_cut(lead, rate, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    assert res.verdict == ref.verdict == "chatter" and abs(res.chatter_hz / ref.chatter_hz - 1) < 1e-3
    assert [g.kind for g in res.segments] == [g.kind for g in ref.segments]
    t0 = 0.8 + 0.0131  # the zeros added and the MP3 decoder's own 13 ms at the start
    for g, h in zip(res.segments, ref.segments):
        assert abs(g.start_s - t0 - max(h.start_s - 0.0131, 0)) < 0.1 and g.verdict == h.verdict
    assert res.criterion["digital_silence_s"][0] == [0.0, pytest.approx(t0, abs=1e-3)]


def test_a_speed_given_in_rev_per_s_is_named():
    """'--rpm 107.7' for a spindle at 6460 rpm (107.7 rev/s): no spindle harmonics near 107.7 rpm, and the comb at
    60 × that stands out in the real recording — refused, naming rpm and the speed; at the right speed nothing of the
    kind."""
    rec = real_record()
    with pytest.raises(InputError, match="rev/s") as exc:
        analyse_cut(rec.samples, rec.rate_hz, rpm=107.7, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert exc.value.field == "rpm"
    rpm = float(str(exc.value).split("but near ")[1].split(" rpm")[0])
    assert abs(rpm / 6460 - 1) < 0.01
    ok = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert not any("rev/s" in w for w in ok.criterion["warnings"])


@pytest.mark.slow  # 5–8 s: the fast tier stays under 3 min
def test_a_record_that_does_not_hear_the_spindle_is_refused_not_judged(tmp_path, capsys):
    """White noise (a microphone left unplugged, a wrong file) was "chatter" in 7 of 12 records of 20 s: without
    spindle harmonics "strong" (against the strongest harmonic) holds for any noise peak, and one significant peak
    in ~20 windows passed. Refused, naming rpm. A record whose spindle is not heard keeps its verdict only where a
    chatter line stands ≥ 20 dB out, with a warning — the real recording (6460 rpm) given 8000 rpm, whose best comb
    lay at the range's edge (7760 rpm, where it was read and judged), saying where the harmonics do stand out. A
    speed given exactly (tolerance 0) is read there alone."""
    import soundfile as sf

    rate = 44100.0
    for seed in range(3):
        x = np.random.default_rng(seed).normal(0.0, 1e-3, int(10 * rate))
        with pytest.raises(InputError, match="no spindle harmonics stand out") as exc:
            analyse_cut(x, rate, rpm=6500, teeth=2)
        assert exc.value.field == "rpm"
        with pytest.raises(InputError, match="no spindle harmonics stand out"):
            analyse_cut(x, rate, rpm=6500, teeth=2, rpm_tolerance=0.0)
    # a long one: its ~1600 frames put the level near the mean, under the bracket the solver was given (a
    # ValueError traceback before the review)
    with pytest.raises(InputError, match="no spindle harmonics stand out"):
        analyse_cut(np.random.default_rng(9).normal(0.0, 1e-3, int(150 * rate)), rate, rpm=6500, teeth=2)
    with pytest.raises(InputError, match="alpha: must be a probability"):
        analyse_cut(x, rate, rpm=6500, teeth=2, alpha=0.0)
    wav = tmp_path / "noise.wav"
    sf.write(wav, x, int(rate), subtype="FLOAT")
    out = tmp_path / "c.json"
    assert main(["cut", str(wav), "--rpm", "6500", "--teeth", "2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "noise.wav" in err and "rpm" in err and not out.exists()

    rec = real_record()
    a, b = 0, int(20 * rec.rate_hz)  # air, cut, chatter
    res = analyse_cut(rec.samples[a:b], rec.rate_hz, rpm=8000, teeth=2, full_scale=rec.full_scale)
    # where the harmonics do stand out: the best comb outside the range, or (since the record's loud blip at 6.6 s is
    # no longer a cut of its own and the cut's stable first second is judged apart) its tooth passing there
    said = [w for w in res.criterion["warnings"] if w.startswith("no spindle harmonics stand out")]
    assert len(said) == 1 and res.verdict == "chatter" and abs(res.chatter_hz / 1067.3 - 1) < 0.01
    at = re.search(r"(?:; at|over the floor at) (\d+) rpm \(-19\.\d %\)", said[0])
    assert at is not None and abs(float(at.group(1)) / 6460 - 1) < 0.005, said[0]
    ok = analyse_cut(rec.samples[a:b], rec.rate_hz, rpm=6460, teeth=2, rpm_tolerance=0.0, full_scale=rec.full_scale)
    assert ok.verdict == "chatter" and abs(ok.chatter_hz / 1067.3 - 1) < 0.01


def test_stereo_channels_in_opposite_polarity_are_not_averaged_away(tmp_path):
    """A swapped lead inverts one channel: the mean of the real recording's channels was then its quantisation
    residue, refused as "clipped at 1.5e-05". Said as it is, naming --channel; either channel alone is the record."""
    import soundfile as sf

    x, rate = sf.read(REAL)
    inv = tmp_path / "inv.wav"
    sf.write(inv, np.c_[x[:, 0], -x[:, 0]], rate, subtype="PCM_16")
    with pytest.raises(InputError, match="channels cancel when averaged.*--channel"):
        read_cut_record(inv)
    one = read_cut_record(inv, channel=1)
    res = analyse_cut(one.samples, one.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=one.full_scale)
    assert res.verdict == "chatter" and abs(res.chatter_hz / 1067.4 - 1) < 0.002


def test_the_stereo_check_s_spectra_taken_in_chunks_are_scipys_welch():
    """The stereo check's channel spectra are averaged 128 frames at a time (all at once SciPy's ``welch`` held each
    frame twice: 1.8 GB for 10.5 min of stereo, the ``cut`` command's peak 2.3 GB against 1.0 GB in chunks,
    2026-12-06): the same density as ``scipy.signal.welch`` over the whole record, to float32's rounding, at any
    chunk size, a record length that leaves a part frame at the end included."""
    from scipy.signal import welch

    from toolpoint.io.records import _welch

    x = np.random.default_rng(11).standard_normal((200_003, 2)).astype(np.float32)
    f, p = welch(x, 44100.0, nperseg=4096, detrend=False, axis=0)
    for frames in (1, 7, 128, 10_000):
        f2, p2 = _welch(x, 44100.0, 4096, frames=frames)
        np.testing.assert_array_equal(f2, f)
        np.testing.assert_allclose(p2, p, rtol=2e-6)


def test_stereo_microphones_apart_are_not_averaged_into_a_notch(tmp_path, capsys):
    """Two microphones a few cm apart hear a source off their axis at different times, and their mean has notches at
    odd multiples of 1/(2τ). The real recording's channel with a copy of itself 0.47 ms later: the mean notched its
    1067 Hz chatter out (read as chatter at 2135 Hz, its air as cutting). The reader sees the mean lose the band
    (under a quarter of the channels' power in a third octave) and reads the loudest channel, and says so; the real
    recording's own two channels (side by side: the mean keeps 0.94–1.0 in every band) are averaged as before."""
    import soundfile as sf

    x, rate = sf.read(REAL)
    a = x[:, 0]
    f = np.fft.rfftfreq(a.size, 1 / rate)
    late = np.fft.irfft(np.fft.rfft(a) * np.exp(-2j * np.pi * f * 0.47e-3), a.size)
    path = tmp_path / "apart.wav"
    sf.write(path, np.c_[a, 0.9 * late], rate, subtype="FLOAT")
    rec = read_cut_record(path)
    assert rec.channel.startswith("0 (the loudest") and len(rec.warnings) == 1
    assert "905–1140 Hz" in rec.warnings[0] and "--channel" in rec.warnings[0]
    res = analyse_cut(rec.samples, rate, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1067.3, rel=2e-3)
    assert main(["cut", str(path), "--rpm", "6500", "--teeth", "2", "--out", str(tmp_path / "c.json")]) == 0
    assert "warning: the mean of the 2 channels keeps" in capsys.readouterr().err
    assert json.loads((tmp_path / "c.json").read_text())["channel"].startswith("0 (the loudest")
    real = read_cut_record(REAL)
    assert real.channel == "mean of 2" and real.warnings == ()


@pytest.mark.parametrize("start_s,end_s", [(10.0, 16.0), (10.0, 14.0), (9.6, 14.6), (10.0, 13.0)])
def test_a_record_taken_inside_the_chattering_cut_is_not_split_into_air_and_cut(start_s, end_s):
    """The real recording's chattering stretch cut out as a record of its own. Its chatter waxes and wanes (the
    1067 Hz line by ±5 dB over a second or two), and split by level the quieter part was taken for an air cut: the
    reference against which the chatter was "no new line". 10–16 s and 10–14 s read stable, 9.6–14.6 s chatter at
    2131 Hz. The quieter part's tooth passing stands out as in the loud part, and it holds the chatter: cutting.
    10–13 s also needs the speed of the tooth-passing harmonics (6459 rpm, steady) where the comb followed the
    chatter's family (6386 rpm), which masked the chatter as a spindle line. (Some 2 s windows still read stable with
    two teeth: a chatter alias pulls the speed tracker at their edge, docs/design/shop.md, Limits.)"""
    rec = real_record()
    a, b = int(start_s * rec.rate_hz), int(end_s * rec.rate_hz)
    res = analyse_cut(rec.samples[a:b], rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=rec.full_scale)
    assert all(s.kind != "air" for s in res.segments)
    assert res.verdict == "chatter" and abs(res.chatter_hz / 1067.3 - 1) < 0.01


@pytest.mark.parametrize("rpm,teeth,fc,swing_db,seed", [(6000, 4, 1234.0, 0.0, 0), (9000, 3, 1630.0, 0.0, 1),
                                                        (12000, 2, 2890.0, 10.0, 0), (3000, 4, 731.0, 10.0, 0),
                                                        (18000, 6, 2345.0, 10.0, 1)])
def test_a_cut_without_air_whose_chatter_sets_its_loudness_is_one_cut(rpm, teeth, fc, swing_db, seed):
    # chatter twice the tooth-passing line, waxing and waning by swing_db: the level splits the cut into a louder
    # and a quieter part, and the quieter one was taken for air (stable, or chatter elsewhere, before)
    x, rate, _, _ = shop_record(rpm=rpm, teeth=teeth, chatter_hz=fc, chatter_amp=2.0, mode_hz=fc, air_s=0.0, cut_s=5.0,
                                chatter_swing_db=swing_db, fans=(), seed=seed)
    res = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
    assert all(s.kind != "air" for s in res.segments)
    assert res.verdict == "chatter" and abs(res.chatter_hz / fc - 1) < 0.01


def test_air_whose_spindle_lines_stand_out_as_far_as_the_chattering_cut_s_stays_air():
    # a spindle ringing in air (lines 1/k in quiet room noise) at 25 000 rpm: its tooth-passing harmonics stand out in
    # air about as far as heavy chatter leaves them in the cut, so by prominence alone the air was cutting and the
    # chatter lost its reference. The air does not hold the chatter: it stays air, with the cut's bounds
    for amp, seed in ((1.0, 0), (3.0, 1), (10.0, 0)):
        x, rate, t0, t1 = shop_record(rpm=25000, teeth=4, chatter_hz=1275.0, chatter_amp=amp, mode_hz=1275.0,
                                      cut_s=2.0, air_lines=1.0, fans=(), noise=0.01, seed=seed)
        res = analyse_cut(x, rate, rpm=25000, teeth=4, full_scale=1.0)
        assert res.segments[0].kind == "air" and res.segments[-1].kind == "air"
        cut = [s for s in res.segments if s.kind != "air"]
        assert abs(cut[0].start_s - t0) < 0.2 and abs(cut[-1].end_s - t1) < 0.2
        assert res.verdict == "chatter" and abs(res.chatter_hz / 1275.0 - 1) < 0.01


@pytest.mark.parametrize("attack_s,release_s", [(0.05, 2.0), (0.5, 0.5)])
def test_the_real_recording_through_a_phone_s_gain_control_keeps_its_air_cut(attack_s, release_s):
    """The real recording (its first 20 s: air, entry, cutting that chatters, exit, air) through a phone's gain
    control: the control brings the chattering cut under the air by the band's median power (−22 dB in air, −29 to −34
    in the cut), and split by level the air was taken for the cut — "chatter at 1770.7 Hz", a machine line of the air,
    without a warning. The loud part has no tooth passing (2–3 dB over noise), the quiet part has (7–8 dB), and the
    air it leaves does not hold the cut's chatter: the level is upside down."""
    rec = real_record()
    n = int(20 * rec.rate_hz)
    x = phone_agc(rec.samples[:n], rec.rate_hz, attack_s, release_s)
    res = analyse_cut(x, rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    assert res.segments[0].kind == "air" and res.segments[0].end_s > 5.0
    entry = next(s for s in res.segments if s.kind == "entry")
    assert 6.0 < entry.start_s < 7.5
    assert res.verdict == "chatter" and abs(res.chatter_hz / 1067.3 - 1) < 0.01
    assert any("gain control" in w for w in res.criterion["warnings"])


@pytest.mark.slow  # 3–4 s: the fast tier read 175–190 s on clean clones of the shared VM (limit 3 min)
def test_the_tone_test_holds_its_false_alarm_rate_on_noise(monkeypatch):
    """The tone test's level t_α against what it claims: parts of n Hann frames of white noise, judged as `_judge`
    judges them (the block-median floor over the unmasked bins), exceed it in about α of the parts. The χ² level with
    Welch's ν used before held α = 0.1 for 0.29–0.38 of these parts (its floor's own error and the overlapping
    frames' heavier tail ignored) and fails this."""
    from toolpoint.shop import detect as d

    rate, f_nom = 44100.0, 6500 / 60
    L = 16336  # the frames analyse_cut takes at 6500 rpm, hop a quarter
    hop = L // 4
    x = np.random.default_rng(7).normal(size=int(240 * rate))
    P, _ = d._stft(x, L, hop)
    freq = np.fft.rfftfreq(L, 1 / rate)
    df = rate / L
    keep, _ = d._harmonic_mask(freq, (freq >= 54) & (freq <= 10_000), f_nom, f_nom, df)
    nu1, thr = d._welch_dof(L, hop), d._tone_threshold(L, hop)
    for n in (4, 10):
        parts = P[: P.shape[0] // n * n].reshape(-1, n, P.shape[1]).mean(axis=1)
        floor = d._block_floor(parts, keep) / d._chi2_median_ratio(nu1(n))
        zmax = np.where(keep, parts / floor, 0.0).max(axis=1)
        for alpha, lo, hi in ((0.1, 0.03, 0.16), (0.01, 0.0, 0.03)):
            rate_seen = float(np.mean(zmax > thr(n, int(keep.sum()), alpha)))
            assert lo <= rate_seen <= hi, (n, alpha, rate_seen, parts.shape[0])
    # long parts (a whole record's frames): the level from the Toeplitz symbol's eigenvalues, grouped, against the
    # level from the exact eigenvalues, at 100 and 250 frames
    exact = [d._t_alpha(L, hop, n, 3600, 0.01) for n in (100, 250)]
    monkeypatch.setattr(d, "_EIG_EXACT_MAX", 64)
    d._t_alpha.cache_clear()
    try:
        symbol = [d._t_alpha(L, hop, n, 3600, 0.01) for n in (100, 250)]
    finally:
        d._t_alpha.cache_clear()
    assert np.allclose(symbol, exact, rtol=5e-3), (symbol, exact)


def test_the_tone_level_s_saddlepoint_solves_its_equation():
    """The saddlepoint ŝ of :func:`_t_alpha`'s tail, K'(ŝ) = Σ w μ / (1 − μ ŝ) = x, by Newton's steps on 1/K' (3–18
    where bisection took 100), against SciPy's ``brentq`` on each x alone: the left tail (ŝ far below 0), by the mean
    (ŝ ~ 1e-3) and near the pole 1 / max μ, for few overlapping frames (exact eigenvalues) and many (the Toeplitz
    symbol's, grouped)."""
    from scipy.optimize import brentq

    from toolpoint.shop import detect as d

    L, hop = 8820, 2205
    w = np.hanning(L)
    rho = [float(np.dot(w[:L - k * hop], w[k * hop:]) / np.dot(w, w)) for k in range(1, 4)]
    x = np.array([0.05, 0.3, 0.9, 0.999, 1.001, 1.2, 3.0, 20.0, 200.0])
    for n in (3, 40, 1000):
        mu, wt = d._overlap_eigenvalues(rho, n)
        assert abs(float(wt @ mu) - 1.0) < 1e-12  # the mean of Σ μ E is 1: K'(0) = 1
        got = d._saddlepoint(mu, wt, x, -1e3 * n / x.min())
        top = 1.0 / mu.max()
        for xi, si in zip(x, got):
            k1 = lambda s: float(np.sum(wt * mu / (1 - mu * s))) - xi  # noqa: E731
            lo = -1.0
            while k1(lo) > 0:
                lo *= 2
            ref = brentq(k1, lo, top * (1 - 1e-12), xtol=1e-15, rtol=1e-14, maxiter=500)
            assert abs(si - ref) <= 1e-9 * max(abs(ref), 1e-3), (n, xi, si, ref)


def test_a_real_microphone_record_that_is_no_cut_is_refused(tmp_path, capsys):
    """The pyuff project's sample microphone time history (UFF58b, 79 292 samples; tests/data/pyuff, MIT), a file
    nobody here made and no record of a cut: at 3000 and 6000 rpm and 4 teeth it read "chatter at 1814.7 Hz" (exit 0,
    "harmonics not found"), at 9000–18000 rpm "stable". It does not hear a spindle at any of them: refused, naming
    the file and rpm, nothing written."""
    rec = Path(__file__).resolve().parents[1] / "data" / "pyuff" / "Sample_UFF58b_bin.uff"
    for rpm in ("3000", "6000", "12000"):
        out = tmp_path / f"c{rpm}.json"
        assert main(["cut", str(rec), "--rpm", rpm, "--teeth", "4", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "Sample_UFF58b_bin.uff" in err and "rpm" in err, err
        assert "no spindle harmonics stand out" in err and not out.exists()


def _teeth_warning(res):
    return [w for w in res.criterion["warnings"] if "spindle harmonics that stand out in the" in w]


@pytest.mark.slow  # 7–9 s: the fast tier read 177 s on the shared VM (limit 3 min)
def test_a_tooth_count_the_record_contradicts_is_warned():
    """A wrong --teeth (a slip no range check catches) moves the tooth-passing aliases the chatter test looks for,
    the split into air and cut and the Harmonizer speed. The spindle harmonics that stand out in the stable cut
    keep the spacing of the cutter's tooth passing: where another spacing explains them better (Otsu's criterion,
    ``_spacing``), it is warned. Synthetic shop records (runout lines 0.1 of the tooth harmonics), and the real
    recording (2 teeth at 6460 rpm), given 3 teeth: it was chatter at 596 Hz in fourteen segments of air, entry,
    cut and exit, against 1067 Hz in one cut with 2, without a word."""
    for teeth, wrong in ((2, 3), (3, 2), (3, 4), (4, 3), (4, 5), (4, 2), (2, 1)):
        x, rate, *_ = shop_record(rpm=6000, teeth=teeth, seed=teeth + 10 * wrong)
        assert not _teeth_warning(analyse_cut(x, rate, rpm=6000, teeth=teeth, full_scale=1.0)), (teeth, wrong)
        w = _teeth_warning(analyse_cut(x, rate, rpm=6000, teeth=wrong, full_scale=1.0))
        assert len(w) == 1 and f"multiples of {teeth} ({teeth * 100:.1f} Hz" in w[0] and "check --teeth" in w[0], w
    rec = real_record()
    right = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=2, full_scale=rec.full_scale)
    assert not _teeth_warning(right)
    res = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=3, full_scale=rec.full_scale)
    w = _teeth_warning(res)
    # the tooth passing in the cut, 215.3 Hz by hand; the spindle wanders 0.1–0.2 % (215.6–215.8 Hz at the entry and
    # exit); given 3 teeth, 215.4 Hz since the tracker's second look in longer frames (2026-12-07)
    assert len(w) == 1 and "not of the 3 teeth given" in w[0], w
    f_t = float(re.search(r"multiples of 2 \(([\d.]+) Hz", w[0]).group(1))
    assert abs(f_t - 215.3) <= 0.2, w


def test_the_speed_is_tracked_on_the_harmonics_that_hold_still():
    """The speed is tracked frame by frame on the four lowest tooth-passing harmonics, or on the four lowest spindle
    harmonics where those wander less over as many frames: both follow one spindle, and a set whose windows hold
    another family's lines wanders with it. The real recording (2 teeth at 6460 rpm by its lines) given the values
    its source project's plot script uses, 12500 rpm and 4 teeth, or 6567 rpm (its file name) and 3 teeth: the
    windows of these readings' weak tooth harmonics hold the chatter's aliases (861 Hz beside 852 Hz, 1067 − 215),
    the track wandered 0.9–1.4 % during the chatter, the masks over that range hid the 1067 Hz line and "chatter at
    599 Hz" was read. A maximum at a window's edge is no peak: a 2-tooth cut at 6460 rpm given 12500 rpm and 4
    teeth (its spindle, at 2 × 6460 by the 4-tooth reading, 3.4 % out of the range searched) was tracked on the
    flank of its 861 Hz line at the edge of a window, 12877 rpm, and read "chatter at 107.6 Hz", its own spindle
    line, once the tracker's frames were long enough to resolve the flank."""
    rec = real_record()
    for rpm, teeth in ((12500, 4), (6567, 3)):
        res = analyse_cut(rec.samples, rec.rate_hz, rpm=rpm, teeth=teeth, full_scale=rec.full_scale)
        assert res.verdict == "chatter" and abs(res.chatter_hz / 1067.3 - 1) < 0.01, (rpm, teeth, res.chatter_hz)
    x, rate, *_ = shop_record(rpm=6460, teeth=2, chatter_hz=1503.0, chatter_amp=0.5, cut_s=4.0, seed=0)
    res = analyse_cut(x, rate, rpm=12500, teeth=4, full_scale=1.0)
    assert res.verdict == "chatter" and abs(res.chatter_hz / 1503.0 - 1) < 0.01, res.chatter_hz


def test_a_spindle_heard_by_its_own_lines_is_judged():
    """A housing accelerometer on a slot with an even tooth count hears hardly any tooth passing: a simulated
    record of EM28-80 at 4827 rpm stood 24, 18 and 24 dB out at 1×, 2× and 4× (its first tooth harmonic) and 0 dB
    over 40 harmonics, and was refused as "no spindle harmonics stand out". Three of the eight lowest spindle
    harmonics standing out at one speed are the spindle heard: such records (white noise, 4.5 s at 25.6 kHz, the
    cut 0.7–3.8 s) are judged stable, each of which the rule before refused; one line alone is still refused."""
    rate, rpm = 25600.0, 4827.0
    f_s = rpm / 60
    t = np.arange(int(4.5 * rate)) / rate
    cut = ((t > 0.7) & (t < 3.8)).astype(float)
    for seed, amp in enumerate((0.3, 0.5, 1.0)):
        rng = np.random.default_rng(seed)
        noise = rng.standard_normal(t.size) * (1 + cut)  # chips double the floor in the cut
        lines = amp * np.sin(2 * np.pi * f_s * t + 1.0) + 0.5 * amp * np.sin(2 * np.pi * 2 * f_s * t + 2.0)
        tooth = 2 * amp * cut * np.sin(2 * np.pi * 4 * f_s * t + 0.3)
        res = analyse_cut(noise + lines + tooth, rate, rpm=rpm, teeth=4)
        assert res.verdict == "stable" and abs(res.rpm / rpm - 1) < 1e-3, (amp, res.rpm)
        with pytest.raises(InputError, match="no spindle harmonics stand out"):
            analyse_cut(noise + 2 * amp * np.sin(2 * np.pi * f_s * t), rate, rpm=rpm, teeth=4)


def test_a_weak_steady_chatter_family_is_warned_of_and_a_strong_one_is_not():
    """A chatter line weaker than "strong" (``dominance``) is chatter only by its tooth-passing aliases, and a stable
    cut near its limit makes the same family under the cutting noise (docs/design/shop.md, *Cutting noise*): such a
    verdict says so; a strong line does not."""
    for amp, weak in ((0.1, True), (0.5, False)):
        x, rate, _, _ = shop_record(rpm=6000.0, teeth=4, chatter_hz=1137.0, chatter_amp=amp, cut_s=3.0, seed=1)
        r = analyse_cut(x, rate, rpm=6000.0, teeth=4, full_scale=1.0)
        assert r.verdict == "chatter" and abs(r.chatter_hz - 1137.0) < 1.0
        dom = max(s.dominance for s in r.segments if s.kind == "cut" and s.verdict == "chatter")
        assert (dom < r.criterion["dominance"]) == weak
        said = [w for w in r.criterion["warnings"] if "rests on a weak line" in w]
        assert bool(said) == weak, (amp, r.criterion["warnings"])
        if weak:
            assert "1137.2 Hz" in said[0] and "-20 dB" in said[0]


def test_a_tone_family_under_the_alias_bar_is_chatter_and_a_tone_with_sidebands_at_the_tooth_passing_only_is_not():
    """A steady line 32 dB under the strongest tooth-passing harmonic (under the alias rule's 27 dB), 26 dB over its
    neighbours and new with the cut: with its regenerative family f + j f_t at j = ±1 and ±2 it is chatter (the
    tone-family rule: saturated chatter under a resonant harmonic, docs/design/shop.md, *Chatter under a resonant
    harmonic*); with lines at ±f_t alone — a stray tone the tooth passing amplitude-modulates — it stays stable."""
    rpm, teeth, f0 = 9000.0, 4, 1733.0
    f_t = teeth * rpm / 60
    for fam, want in (((-1, 1), "stable"), ((-2, -1, 1, 2), "chatter")):
        x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, noise=0.02, seed=3)
        t = np.arange(x.size) / rate
        on = np.clip((t - t0) / 0.05, 0, 1) * np.clip((t1 - t) / 0.05, 0, 1)
        y = np.sin(2 * np.pi * f0 * t) + sum(0.3 * np.sin(2 * np.pi * (f0 + j * f_t) * t + j) for j in fam)
        r = analyse_cut(x + 0.006 * on * y, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
        cut = max((s for s in r.segments if s.kind == "cut"), key=lambda s: s.end_s - s.start_s)
        assert abs(cut.peak_hz - f0) < 1.0 and cut.dominance < r.criterion["alias_dominance"]
        assert cut.line_db >= 20 and cut.n_alias == len(fam)
        assert r.verdict == want, fam
        if want == "chatter":
            assert abs(r.chatter_hz - f0) < 1.0
            assert any("rests on a weak line" in w for w in r.criterion["warnings"])


def _spin(air, rate, seconds, up):
    """The real recording's own air cut played at a speed rising from 0.1 × to 1 × (``up``) or falling from 1 × to
    0.1 ×, its level with it (0.3 → 1 or 1 → 0.3): the spindle running up or coasting down, every machine line
    sweeping as a spindle's do."""
    n = int(seconds * rate)
    u = np.arange(n) / n
    speed = 0.1 + 0.9 * u if up else 1.0 - 0.9 * u
    pos = np.cumsum(speed)
    return np.interp(pos, np.arange(air.size), air) * (0.3 + 0.7 * u if up else 1.0 - 0.7 * u)


@pytest.mark.parametrize("before,after", [("room", None), pytest.param("up", None, marks=pytest.mark.slow),
                                          pytest.param(None, "down", marks=pytest.mark.slow), ("up", "down")])
def test_a_spindle_not_at_speed_at_the_record_s_ends_is_left_out(before, after):
    """A phone started before the spindle and stopped after it: the real recording (its first 25 s: air at speed,
    entry, cutting that chatters, exit, air) behind 2 s of room noise or 0.5 s of it and a 3 s run-up, and before a
    3 s coast-down. Split by level, the quiet start was the air and the air at speed "cutting" — judged against
    nothing, its machine lines chattered ("chatter at 1069 Hz" from 2 s on, a 2330 Hz line in the air after the cut).
    Left out, the rest reads as the record alone: the same segments, shifted, and the same chatter."""
    rec = real_record()
    rate = rec.rate_hz
    x = rec.samples[:int(25 * rate)]
    air = rec.samples[int(25 * rate):int(40 * rate)]
    room = 0.002 * np.random.default_rng(1).standard_normal(int((2.0 if before == "room" else 0.5) * rate))
    head = {None: np.zeros(0), "room": room, "up": np.r_[room, _spin(air, rate, 3.0, True)]}[before]
    tail = {None: np.zeros(0), "down": np.r_[_spin(air, rate, 3.0, False), room]}[after]
    plain = analyse_cut(x, rate, rpm=6500, teeth=2, full_scale=1.0)
    res = analyse_cut(np.r_[head, x, tail], rate, rpm=6500, teeth=2, full_scale=1.0)
    t0 = head.size / rate
    off = res.criterion["spindle_off_s"]
    if before:  # left out up to where the air at speed begins (within the 0.37 s frames and 0.5 s smoothing)
        assert off[0][0] == 0.0 and abs(off[0][1] - t0) < 0.5
    if after:
        assert abs(off[-1][0] - (t0 + x.size / rate)) < 0.5 and off[-1][1] == pytest.approx((x.size + head.size
                                                                                               + tail.size) / rate)
    assert [s.kind for s in res.segments] == [s.kind for s in plain.segments]
    for s, p in zip(res.segments[1:-1], plain.segments[1:-1]):  # the ends of the first and last air move with off
        assert abs(s.start_s - t0 - p.start_s) < 0.05 and abs(s.end_s - t0 - p.end_s) < 0.05
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(plain.chatter_hz, rel=1e-3)
    # the chattering stretch is the plain record's (the first second of the cut is not compared: its verdict turns
    # with a shift of the record by 20–50 ms on the plain record too, a 1671 Hz machine line that a gain control
    # dipped by 20 dB at the entry recovering within it, read as growth)
    chat = [v for s in res.segments if s.verdict == "chatter" and s.end_s - s.start_s > 3
            for v in (s.start_s - t0, s.end_s - t0)]
    assert chat and chat == pytest.approx([v for s in plain.segments if s.verdict == "chatter" and s.end_s - s.start_s
                                           > 3 for v in (s.start_s, s.end_s)], abs=0.05)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_stable_cut_behind_a_run_up_is_not_chatter(seed):
    """A synthetic shop record (fans at 617 and 1813 Hz, the spindle's lines in air) behind 0.5 s of room noise and a
    3 s run-up, before a 3 s coast-down and room noise: judged as the record alone. Before, the quiet start was the air
    and the fans of the air at speed were "new": every stable record of seeds 0–3 read "chatter at 617 / 1813 Hz", and
    the chattering ones reported a fan's frequency for three of four."""
    for chatter in (None, 1234.0):
        x, rate, t0, t1 = shop_record(rpm=6000.0, teeth=4, air_s=2.0, cut_s=2.0, chatter_hz=chatter, chatter_amp=0.5,
                                      seed=seed)
        air = np.tile(x[:int(t0 * rate)], 3)
        room = 0.002 * np.random.default_rng(seed).standard_normal(int(0.5 * rate))
        y = np.r_[room, _spin(air, rate, 3.0, True), x, _spin(air, rate, 3.0, False), room]
        res = analyse_cut(y, rate, rpm=6000, teeth=4, full_scale=1.0)
        assert res.verdict == ("stable" if chatter is None else "chatter"), (chatter, res.chatter_hz)
        if chatter is not None:
            assert res.chatter_hz == pytest.approx(chatter, rel=0.01)
        assert [round(a, 1) for a, _ in res.criterion["spindle_off_s"]] == [0.0, pytest.approx(9.5, abs=0.2)]


def test_a_spindle_the_air_does_not_let_one_hear_keeps_its_air():
    """Where the air cut holds no spindle lines to hear (a quiet spindle under room noise), nothing is at speed
    before the cut: the air stays the reference, nothing is left out, and the verdicts are the record's."""
    for chatter in (None, 1234.0):
        x, rate, t0, t1 = shop_record(rpm=3000.0, teeth=3, noise=0.2, air_lines=0.0, chatter_hz=chatter, seed=3)
        res = analyse_cut(x, rate, rpm=3000, teeth=3, full_scale=1.0)
        assert "spindle_off_s" not in res.criterion
        assert res.segments[0].kind == "air" and res.segments[-1].kind == "air"
        assert res.verdict == ("stable" if chatter is None else "chatter")


@pytest.mark.parametrize("seed", [0, 1])
def test_a_spindle_stopped_between_two_cuts_is_left_out(seed):
    """One record of a session: a stable cut, the spindle coasting down, 1 s standing still, running up again, and a
    cut that chatters at 1234 Hz. Before, the stop was the quietest level, so it became the air cut and the air at
    speed "cutting": the fans (617 and 1813 Hz) of the air chattered, the first cut was not found as a cut. The stop is
    left out and the two stretches at speed are judged together: two cuts, the first stable, the second chatter, at
    their own times in the record."""
    x1, rate, a0, a1 = shop_record(rpm=6000.0, teeth=4, air_s=2.0, cut_s=2.0, seed=seed)
    x2, _, b0, b1 = shop_record(rpm=6000.0, teeth=4, air_s=2.0, cut_s=2.0, chatter_hz=1234.0, chatter_amp=0.5,
                                seed=seed + 10)
    air = np.tile(x1[:int(a0 * rate)], 3)
    room = 0.002 * np.random.default_rng(seed).standard_normal(int(1.0 * rate))
    stop = np.r_[_spin(air, rate, 3.0, False), room, _spin(air, rate, 3.0, True)]
    res = analyse_cut(np.r_[x1, stop, x2], rate, rpm=6000, teeth=4, full_scale=1.0)
    t2 = (x1.size + stop.size) / rate  # where the second record starts
    (u, v), = res.criterion["spindle_off_s"]
    assert u == pytest.approx(x1.size / rate, abs=0.3) and v == pytest.approx(t2, abs=0.3)
    cuts = res.cuts
    assert [c[2] for c in cuts] == ["stable", "chatter"], cuts
    assert cuts[1][3] == pytest.approx(1234.0, rel=0.01)
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1234.0, rel=0.01)
    # each cut where it lies (its entry from the tool's entry to its exit's end, within a frame's quarter)
    assert cuts[0][:2] == pytest.approx((a0, a1), abs=0.1)
    assert cuts[1][:2] == pytest.approx((t2 + b0, t2 + b1), abs=0.1)
    assert all(not (u < s.start_s < v or u < s.end_s < v) for s in res.segments)  # nothing judged in the stop
    assert np.all(np.diff(res.time_s) > 0) and not np.any((res.time_s > u + 0.3) & (res.time_s < v - 0.3))


def test_the_real_recording_twice_with_the_spindle_stopped_between():
    """The real recording's first 25 s (air, a cut that chatters, air), the spindle stopped (a 3 s coast-down of its
    air, 1.5 s of room noise, a 3 s run-up), and the same 25 s again: each copy reads as the record alone. Before, the
    second copy's air at speed was "chatter at 1069 Hz" and its air after the cut "chatter at 2330 Hz"."""
    rec = real_record()
    rate = rec.rate_hz
    x = rec.samples[:int(25 * rate)]
    air = rec.samples[int(25 * rate):int(40 * rate)]
    room = 0.002 * np.random.default_rng(1).standard_normal(int(1.5 * rate))
    stop = np.r_[_spin(air, rate, 3.0, False), room, _spin(air, rate, 3.0, True)]
    plain = analyse_cut(x, rate, rpm=6500, teeth=2, full_scale=1.0)
    res = analyse_cut(np.r_[x, stop, x], rate, rpm=6500, teeth=2, full_scale=1.0)
    t2 = (x.size + stop.size) / rate
    (u, v), = res.criterion["spindle_off_s"]
    assert u == pytest.approx(x.size / rate, abs=0.5) and v == pytest.approx(t2, abs=0.5)
    assert len(res.cuts) == 2 and [c[2] for c in res.cuts] == ["chatter", "chatter"]
    for (a, b, _, hz), shift in zip(res.cuts, (0.0, t2)):
        (pa, pb, _, phz), = plain.cuts
        assert a - shift == pytest.approx(pa, abs=0.05) and b - shift == pytest.approx(pb, abs=0.05)
        assert hz == pytest.approx(phz, rel=2e-3)


def test_the_real_recording_s_stable_cutting_reads_stable_wherever_the_record_starts():
    """The real recording's first 12 s (air, entry at 6.9 s, stable cutting, chatter at 1068 Hz from about 9.5 s) cut
    at its start by 10–150 ms, as a recorder started a moment later would. As the tool comes into the part its forced
    lines rise by ~13 dB over 0.7 s and the lines the cutting drives (a 1671 Hz machine line, a 596 Hz ring) by 20–27
    dB with them: read as growth, the first second of cutting was "chatter at 596 / 1672 Hz" for 16 of 20 such
    starts (0–190 ms), though the record's own start reads it stable. Read against the forced lines' rise, 18 of 20
    read it stable (docs/design/shop.md, *A line that rises with the engagement*)."""
    rec = real_record()
    rate = rec.rate_hz
    for shift in (0.01, 0.02, 0.05, 0.15):
        res = analyse_cut(rec.samples[int(shift * rate):int(12 * rate)], rate, rpm=6500, teeth=2, full_scale=1.0)
        cut = [s for s in res.segments if s.kind == "cut"]
        assert cut[0].verdict == "stable" and all(s.verdict == "stable" for s in cut if s.end_s + shift < 8.8), (
            shift, [(round(s.start_s, 2), s.verdict, s.chatter_hz) for s in cut])
        assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1068.0, rel=2e-3)
        assert min(s.start_s for s in cut if s.verdict == "chatter") + shift < 9.7


@pytest.mark.parametrize("start_s", [6.4, 6.6])
def test_the_real_recording_started_just_before_the_tool_comes_in_keeps_its_air(start_s):
    """The real recording started 0.3–0.5 s before its entry (6.9 s), under an air cut's 0.6 s: read as cutting, that
    air put the entry into the first judged window, "chatter at 1068–1069 Hz" from the record's start (the code before
    2026-12-06), where the whole record reads its first two seconds of cutting stable. Kept as air, it reads them as the
    whole record does."""
    rec = real_record()
    rate = rec.rate_hz
    res = analyse_cut(rec.samples[int(start_s * rate):], rate, rpm=6500, teeth=2, full_scale=1.0)
    assert [s.kind for s in res.segments][:2] == ["air", "entry"]
    cut = _cut_segments(res)
    assert cut[0].verdict == "stable" and cut[0].end_s + start_s > 8.0, [(s.start_s, s.verdict) for s in cut]
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1067.3, rel=2e-3)


def _takes(cases, gains_db, noise, rpm=6000.0, teeth=4):
    """Takes of ``shop_synth`` (5 s air, 2 s cut, 5 s air; each ``cases`` entry a chatter frequency Hz or None, and a
    seed) joined in one record, each brought back to one gain by its fans (``shop_record`` scales each take by its own
    peak; the fans are 0.3 in every take) and then given its gain in ``gains_db``: (record / its peak × 0.9, rate,
    [(cut start s, cut end s, chatter Hz or None)], the joins s)."""
    xs, truth, joins, off = [], [], [], 0.0
    for (hz, seed), g in zip(cases, gains_db):
        x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, air_s=5.0, cut_s=2.0, chatter_hz=hz, chatter_amp=1.0,
                                      noise=noise, seed=seed)
        t = np.arange(int(5.0 * rate)) / rate
        fan = 2 * abs(np.mean(x[:t.size] * np.exp(-2j * np.pi * 617.0 * t)))
        xs.append(x * 0.3 / fan * 10 ** (g / 20))
        truth.append((off + t0, off + t1, hz))
        off += x.size / rate
        joins.append(off)
    x = np.concatenate(xs)
    return 0.9 * x / np.abs(x).max(), rate, truth, joins[:-1]


def _each_take_right(res, truth):
    """Each take's cut found where it was made and judged as made (chatter within 1 % of its frequency)."""
    for a, b, hz in truth:
        segs = [s for s in res.segments if s.kind == "cut" and s.end_s > a and s.start_s < b]
        ch = [s for s in segs if s.verdict == "chatter"]
        assert segs, (a, "no cut found")
        if hz is None:
            assert not ch, (a, [s.chatter_hz for s in ch])
        else:
            assert ch and abs(max(ch, key=lambda s: s.end_s - s.start_s).chatter_hz / hz - 1) < 0.01, (a, hz)
    assert all(any(a - 0.3 < s.end_s and s.start_s < b + 0.3 for a, b, _ in truth)
               for s in res.segments if s.kind == "cut"), "a cut where none was made"


@pytest.mark.slow
def test_takes_recorded_at_different_gains_and_joined_are_each_judged_at_one_gain():
    """Five takes joined in one sound file, recorded at gains up to 15 dB apart (a phone moved, a recorder's gain
    turned): one air reference for all took the louder takes' fans for chatter ("chatter at 617 Hz" on a stable cut)
    before 2026-12-06 (late). A step of the whole record's level — every line and the noise floor alike, at once —
    is read and each part scaled to one gain; the step is said, at its join."""
    cases = [(None, 11), (1234.0, 12), (None, 13), (2345.0, 14), (None, 15)]
    x, rate, truth, joins = _takes(cases, [-3.0, 0.0, 12.0, 12.0, 12.0], 0.05)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    _each_take_right(res, truth)
    steps = res.criterion["gain_steps"]
    # the 3 dB step is under the 4 dB looked for, and harmless; the 12 dB one read by the lines' shift to a dB or two
    assert len(steps) == 1 and abs(steps[0][0] - joins[1]) < 0.05 and abs(steps[0][1] - 12) < 2.5, steps
    assert any(w.startswith("the record's level steps at ") for w in res.criterion["warnings"])
    # a part of the record (--start/--end) says its step in the record's times
    part = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0, span_s=(13.0, 40.0))
    assert np.allclose(part.criterion["gain_steps"], steps, atol=1e-3)
    assert any(w.startswith(f"the record's level steps at {steps[0][0]:.2f} s") for w in part.criterion["warnings"])
    # the same takes at one gain: no step read, nothing said
    x, rate, truth, _ = _takes(cases, [0.0] * 5, 0.05)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    _each_take_right(res, truth)
    assert "gain_steps" not in res.criterion and not any("level steps" in w for w in res.criterion["warnings"])


@pytest.mark.slow
def test_stable_cuts_beside_a_chattering_one_in_a_loud_shop_stay_cuts():
    """Five takes at one gain in a loud shop (room noise 2.0 of ``shop_synth``: its cutting noise drowns the tooth
    passing, which stands out by noise's own 4–6 dB in air and cuts alike): before 2026-12-06 (late) a chattering
    cut's tooth passing, 1–2 dB further out, made each stable cut beside it "like the air" and it was taken for air
    (both records here: a stable take found as no cut). The tooth passing tells air from cut only where it stands
    out somewhere (≥ 4 dB over noise's own)."""
    for chatter, seed in (((1234.0, None, None, 2345.0, None), 41), ((None, 1673.0, None, None, None), 51)):
        x, rate, truth, _ = _takes([(c, seed + i) for i, c in enumerate(chatter)], [0.0] * 5, 2.0)
        _each_take_right(analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0), truth)


@pytest.mark.slow
def test_takes_of_the_real_recording_joined_in_one_record_keep_their_air_cuts():
    """Twelve takes of the real recording's first 30 s (air, entry at 6.9 s, cut to 16.2 s, air) put end to end, each
    beginning as the file does, with the decoder's priming and 45 ms fade-in: as at each join of MP3 takes.
    Counted together, the twelve brief dips passed for a level of their own, and split from the rest they "separated"
    better than air cut and cut: the whole 6 min read as one cut, its air "chatter at 1770.7 Hz" (the code before
    2026-12-06; 20 copies of the whole 63 s recording the same, at 2330 Hz). Now every take has its air, its entry and
    exit where the recording has them, and its chatter at 1067 Hz."""
    rec = real_record()
    rate = rec.rate_hz
    take = rec.samples[:int(30 * rate)]  # it begins as the file does: the decoder's priming, a 45 ms fade-in
    take_s = take.size / rate
    res = analyse_cut(np.tile(take, 12), rate, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1067.3, rel=2e-3)
    assert sum(s.kind == "air" for s in res.segments) == 13
    for kind, at in (("entry", 6.9), ("exit", 16.2)):
        t = np.array([s.start_s for s in res.segments if s.kind == kind])
        assert t.size == 12 and np.all(np.abs(t - take_s * np.arange(12) - at) < 0.4), (kind, t)
    for k in range(12):
        lines = [s.chatter_hz for s in _cut_segments(res) if k * take_s <= s.start_s < (k + 1) * take_s
                 and s.verdict == "chatter"]
        assert any(abs(f - 1067.3) < 2.0 for f in lines), (k, lines)


@pytest.mark.slow
def test_takes_of_the_real_recording_at_different_gains_are_each_judged_at_one_gain():
    """The real recording's first 30 s, then the whole recording 12 dB quieter: two takes of a real shop joined, the
    phone moved away between them. Real air is not the same from take to take: line by line the recording's air
    before its cut and after it differ by 4–6 dB (nine in ten of its lines), and the code before 2026-12-07 asked
    nine in ten within 3 dB of their shift, so it read no step here: the second take's cut went unfound, and 20 ms
    at the record's start read "chatter at 1770 Hz". Now one step is read at the join (−9.8 dB, the lines' median
    shift), and each take's cut chatters at 1067 Hz where it was made, with no cut in the air."""
    rec = real_record()
    rate = rec.rate_hz
    first = rec.samples[:int(30 * rate)]
    join = first.size / rate
    res = analyse_cut(np.r_[first, rec.samples * 10 ** (-12 / 20)], rate, rpm=6500, teeth=2, rpm_tolerance=0.05,
                      full_scale=1.0)
    steps = res.criterion["gain_steps"]
    assert len(steps) == 1 and abs(steps[0][0] - join) < 0.1 and -13 < steps[0][1] < -8, steps
    for t0 in (0.0, join):  # the recording's cut: entry at 6.9 s, chatter from 9.1 s, exit at 16.2 s
        lines = [s.chatter_hz for s in _cut_segments(res) if t0 + 9.5 < s.end_s and s.start_s < t0 + 16.0
                 and s.verdict == "chatter"]
        assert lines and all(abs(f / 1067.3 - 1) < 0.01 for f in lines), (t0, lines)
    assert all(any(t0 + 6.6 < s.end_s and s.start_s < t0 + 16.6 for t0 in (0.0, join)) for s in _cut_segments(res))
    # the plot shows the record at one gain, as judged, and says where it was scaled
    from toolpoint.shop import plot_cut

    fig = plot_cut(res)
    assert [t.get_text() for t in fig.axes[0].texts if "gain step" in t.get_text()] == [
        f" gain step {steps[0][1]:+.1f} dB"]
    assert fig.axes[1].get_ylabel() == "mean power, dB (parts at one gain)"


@pytest.mark.slow
@pytest.mark.parametrize("speed, rate, channel", [(0.75, 44100, None), (0.75, 44100, 0), (1.6, 44100, None),
                                                  (1.0, 48000, None)])
def test_the_real_recording_played_at_another_speed_is_heard_at_that_speed(speed, rate, channel):
    """The real recording resampled: at 48 kHz (a phone's rate), or played at the same rate ``speed`` × as fast — a
    machine whose every sound runs at that speed, the spindle at 6461 × ``speed`` rpm and the chatter at 1067.3 ×
    ``speed`` Hz, from a shop nobody here recorded. At 0.75 × the chatter lies 7.05 Hz under the 5th tooth-passing
    harmonic (9.4 Hz in the recording), and its aliases as near the four lowest tooth harmonics, from which the
    speed is tracked: in the tracker's 0.4 s frames (bins of 2.5 Hz) they pulled the harmonics' peaks, the track
    read the spindle 0.7 % slow for two seconds in mid-cut, the masks widened with it, and "chatter at 1598.8 Hz", an
    alias family's weak line, was read before 2026-12-07 (each channel alone, the mean, at 44.1 or 48 kHz, ±2 or
    ±5 %). A wander that frames twice as long do not read over the same stretch is now another family's, not the
    spindle's (0.04–0.08 % in 0.8 s frames). Each part of the recording's cut (entry at 6.9 s, chatter from 9.1 s,
    exit at 16.2 s) is found where it lies at this speed, and its chatter at its frequency (``channel``: the left
    microphone alone, else the mean of both)."""
    from fractions import Fraction

    import soundfile as sf
    from scipy.signal import resample_poly

    rec = real_record()
    x = rec.samples if channel is None else sf.read(REAL)[0][:, channel]
    f = Fraction(rate / (speed * rec.rate_hz)).limit_denominator(400)  # samples out per sample in
    y = resample_poly(x, f.numerator, f.denominator)
    res = analyse_cut(y, float(rate), rpm=6500 * speed, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    hz = 1067.3 * speed
    assert res.verdict == "chatter" and abs(res.chatter_hz / hz - 1) < 0.01, res.chatter_hz
    cuts = _cut_segments(res)
    assert cuts and all(6.6 / speed < s.start_s and s.end_s < 16.6 / speed for s in cuts), cuts
    chatter = [s for s in cuts if s.verdict == "chatter"]
    assert all(abs(s.chatter_hz / hz - 1) < 0.01 for s in chatter), [s.chatter_hz for s in chatter]
    assert sum(s.end_s - s.start_s for s in chatter) > 0.8 * (16.2 - 9.1) / speed


def test_a_spindle_that_wanders_once_a_second_keeps_its_short_frames_track():
    """The guard of the tracker's second look (above): a spindle whose speed truly wanders, ±0.3 % once a second,
    reads almost steady in 0.8 s frames (0.006 %), which average the wander out; the 0.4 s frames' track, averaged as
    those frames would read it, agrees with them (0.13 %, under ¾ of its own 0.27 %), so the wander is the spindle's
    and its track is kept. Taken for another family's pull, the stable cut read "chatter at 2406 Hz"."""
    x, rate, *_ = shop_record(rpm=6000, teeth=4, air_s=1.5, cut_s=6.0, speed_wander=0.003, wander_hz=1.0, seed=1)
    res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
    assert res.verdict == "stable", res.chatter_hz
    assert res.criterion["speed_tracked"] and 0.002 < res.criterion["speed_wander"] < 0.004


@pytest.mark.parametrize("air_s", [0.6, 0.45, 0.2])
def test_a_short_air_cut_at_the_record_s_start_or_end_is_air_not_cutting(air_s):
    """A recorder started 0.2–0.6 s before the tool comes in, or stopped as soon after it left: air shorter than an
    air cut (0.6 s at 6000 rpm, 1.5 of the 0.4 s frames) is a pause where it lies between two cuts, not at the
    record's ends. Taken for cutting there, it put the entry or the exit (the mode's ring as the tool comes in, the
    tooth passing dying away) into a judged window: stable synthetic cuts read "chatter" at 391–409 Hz, beside the
    400 Hz tooth passing — 2 of 2 seeds with 0.6 s of air at the start, with 0.2–0.6 s at the end (the code before
    2026-12-06). Kept as air, the cut is stable, chatter is heard as with a long air cut, and the cut's length is
    the cut's. With both ends that short the record holds no air cut to compare with, and says so."""
    from toolpoint.shop.update import _cutting_s

    for seed in (0, 1):
        x, rate, t0, t1 = shop_record(rpm=6000.0, teeth=4, air_s=1.0, cut_s=3.0, mode_hz=700.0, seed=seed)
        xc, *_ = shop_record(rpm=6000.0, teeth=4, air_s=1.0, cut_s=3.0, mode_hz=700.0, chatter_hz=1234.0,
                             chatter_amp=0.1, seed=seed)
        k = int((1.0 - air_s) * rate)
        for part in (slice(k, None), slice(0, x.size - k)):
            res = analyse_cut(x[part], rate, rpm=6000.0, teeth=4)
            assert res.verdict == "stable", (seed, [(s.kind, round(s.start_s, 2), s.verdict) for s in res.segments])
            kinds = [s.kind for s in res.segments]
            assert kinds[:2] == ["air", "entry"] and kinds[-2:] == ["exit", "air"]
            assert _cutting_s(res) == pytest.approx(t1 - t0, abs=0.15)  # the cut's length, not the air's with it
            res = analyse_cut(xc[part], rate, rpm=6000.0, teeth=4)
            assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1234.0, rel=2e-3)
        # both ends short: the fans' tones (617, 1813 Hz) cannot be told from chatter without the air, and `cut` says
        # why its "chatter" is in doubt
        res = analyse_cut(x[k:x.size - k], rate, rpm=6000.0, teeth=4)
        assert res.verdict == "chatter" and min(abs(res.chatter_hz - f) for f in (617.0, 1813.0)) < 2.0
        assert any("shorter than an air cut (0.6 s)" in w for w in res.criterion["warnings"]), res.criterion["warnings"]


@pytest.mark.parametrize("seed", [0, 2])
def test_chatter_that_grows_as_the_tool_comes_into_the_part_is_chatter(seed):
    """A growth is read against the forced lines where those rise (the tool coming into the part): chatter that rises
    with them over a 1 s engagement, weak (0.1 of the first tooth harmonic), is still found at its frequency, as with
    the tool in the part at once."""
    for ramp_s in (0.05, 1.0):
        x, rate, *_ = shop_record(rpm=6000.0, teeth=4, air_s=1.5, cut_s=3.0, chatter_hz=1234.0 + 37 * seed,
                                  chatter_amp=0.1, ramp_s=ramp_s, seed=seed)
        res = analyse_cut(x, rate, rpm=6000, teeth=4, full_scale=1.0)
        assert res.verdict == "chatter" and res.chatter_hz == pytest.approx(1234.0 + 37 * seed, rel=0.01), ramp_s


TALK = Path(__file__).resolve().parents[1] / "data" / "voice"


def test_talk_in_the_air_before_a_cut_is_neither_a_cut_nor_the_air_s_reference():
    """Someone talking near the phone in the air cut, at 0.3 × the cut's RMS (−10 dB: a raised voice near a phone
    during a cut of ~85 dB): sentences spoken by espeak-ng (``tests/data/voice``, a speech model nobody here wrote)
    over the shop records of ``shop_synth``. Before 2026-12-06 27 of 60 such records (10 cases × 6 utterances) were
    judged wrong, stable cuts "chattering" at a fan's 617 or 1813 Hz: a loud syllable's frame was a "cut" of its own,
    and the voice in the air's reference raised its floor, so the air was lowered "for a gain control" until the fan
    rose 10 dB over it in the cut. Chatter stays heard at its frequency."""
    cases = [(6000, 4, None, 0), (3000, 2, None, 4), (15000, 2, None, 6), (6000, 4, 1234.0, 1), (9000, 3, 2345.0, 3)]
    assert len(list(_judged_with_talk_in_the_air(cases, 0.3, 1.5))) == 15


def test_talk_as_loud_as_the_cut_in_the_air_is_no_cut():
    """Talk in the air cut as loud as the cut (1 × its RMS): the level split takes the voice for cutting. Before
    2026-12-06 (night) 5 of these 15 records were judged wrong (stable cuts "chattering" at a voice's harmonic). A
    loud run of a sound file whose level comes and goes by ≥ 6 dB as speech does, and whose tooth passing stands out
    as lines no further than in the air (or than noise), beside a cut whose stands ≥ 6 dB further out, is no cut:
    left out, and said so, and called ``talk`` in the segments (``air`` before 2026-12-07). Chatter stays heard at
    its frequency."""
    cases = [(3000, 2, None, 0), (6000, 4, None, 1), (12000, 4, None, 3), (4500, 6, 1234.0, 5), (6000, 4, 1234.0, 6)]
    said = 0
    for res in _judged_with_talk_in_the_air(cases, 1.0, 2.2):
        named = [tuple(map(float, m)) for w in res.criterion["warnings"]
                 for m in re.findall(r"the loud stretch ([\d.]+)–([\d.]+) s is no cut: its level comes and goes", w)]
        said += bool(named)
        # cut.json (and the plot) call the stretch talk, not air: each named stretch is a talk segment, and only they
        talk = [(s.start_s, s.end_s) for s in res.segments if s.kind == "talk"]
        assert len(talk) == len(named) and all(abs(a - ta) < 0.06 and abs(b - tb) < 0.06
                                               for (a, b), (ta, tb) in zip(named, talk)), (named, talk)
        assert all(s.verdict == "air" for s in res.segments if s.kind == "talk")
    assert said >= 10  # (syllables too short to read the level's spread stay cuts, judged: stable here)


def _judged_with_talk_in_the_air(cases, level, scale):
    """Each case (rpm, teeth, chatter Hz or None, seed) of ``shop_synth`` with 6.5 s of air around its 3 s cut, and
    each of ``tests/data/voice``'s sentences added from 0.3 s at ``level`` × the cut's RMS, the sum / ``scale``,
    judged: asserted stable, or chatter at its frequency; each result yielded."""
    import soundfile as sf
    from scipy.signal import resample_poly

    talks = []
    for k in "abc":
        v, r = sf.read(TALK / f"talk_{k}.flac")
        assert r == 22050
        talks.append(resample_poly(v, 2, 1))  # 44.1 kHz
    for rpm, teeth, chatter, seed in cases:
        x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=chatter, chatter_amp=0.5, air_s=6.5, cut_s=3.0,
                                      seed=seed)
        rms = np.sqrt(np.mean(x[int(t0 * rate):int(t1 * rate)] ** 2))
        for v in talks:
            y = x.copy()
            i = int(0.3 * rate)
            y[i:i + v.size] += level * rms * v / np.sqrt(np.mean(v ** 2))
            res = analyse_cut(y / scale, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
            if chatter is None:
                assert res.verdict == "stable", (rpm, res.chatter_hz)
            else:
                assert res.verdict == "chatter" and abs(res.chatter_hz / chatter - 1) < 0.01, (rpm, res.chatter_hz)
            yield res


def test_a_cut_whose_chatter_waxes_and_wanes_beside_a_stable_cut_is_kept():
    """The talk rule's guard (above): two cuts in one sound file, a stable one and one whose chatter waxes and wanes
    by 16 dB at 2 Hz — its level comes and goes as speech does (the rule's spread ≥ 6 dB) — or at 0.4 Hz as the real
    recording's chatter swings: its tooth passing stands out as a cut's, so both are cuts and the record chatters."""
    from toolpoint.shop.detect import _SPEECH_SPREAD_DB, _level_spread_db

    for swing_hz in (2.0, 0.4):
        a, rate, *_ = shop_record(rpm=6000.0, teeth=4, air_s=1.5, cut_s=3.0, seed=3)
        b, _, t0, t1 = shop_record(rpm=6000.0, teeth=4, air_s=1.5, cut_s=3.0, chatter_hz=1234.0, chatter_amp=2.0,
                                   chatter_swing_db=16.0, swing_hz=swing_hz, seed=4)
        if swing_hz == 2.0:
            assert _level_spread_db(b, rate, t0, t1, 100.0) >= _SPEECH_SPREAD_DB  # the level alone would drop it
        res = analyse_cut(np.concatenate([a, b]) / 4, rate, rpm=6000, teeth=4, full_scale=1.0)
        assert res.verdict == "chatter" and abs(res.chatter_hz / 1234.0 - 1) < 0.01, (swing_hz, res.chatter_hz)
        assert not any("is no cut" in w for w in res.criterion["warnings"])
        assert sum(sg.kind == "cut" for sg in res.segments) >= 2


def test_a_record_coded_at_a_low_bit_rate_is_warned_of(tmp_path, capsys):
    """A messenger's voice note is Opus at ~32 kbit/s: on 576 simulated grid records so coded 30 stable cuts were
    "chatter" (0 uncompressed; the coder's artefacts 22–27 dB under the strongest harmonic passed for chatter's
    aliases), at 72 kbit/s none. The reader says so from the file's own codec and mean bit rate; the real recording's
    MP3 (128 kbit/s), the same cut at ~130 kbit/s and FLAC are not warned of."""
    import inspect

    import soundfile as sf

    if "compression_level" not in inspect.signature(sf.write).parameters:  # soundfile < 0.13 cannot set the rate
        pytest.skip("this soundfile cannot choose a coder's bit rate (compression_level: soundfile ≥ 0.13)")
    x, rate = sf.read(REAL)
    part = x[: int(20 * rate)].mean(axis=1)
    low, high, flac = tmp_path / "note.opus", tmp_path / "hq.ogg", tmp_path / "cut.flac"
    sf.write(low, part, 48000, format="OGG", subtype="OPUS", compression_level=0.9)  # the rate is Opus's own
    sf.write(high, part, 48000, format="OGG", subtype="OPUS", compression_level=0.5)
    sf.write(flac, part, int(rate))
    said = read_cut_record(low).warnings
    assert len(said) == 1 and said[0].startswith("coded as Opus at ") and "128 kbit/s or more" in said[0]
    kbps = float(said[0].split(" at ")[1].split(" kbit/s")[0])
    assert 20 < kbps < 80
    for quiet in (high, flac, REAL):
        assert not any("kbit/s" in w for w in read_cut_record(quiet).warnings), quiet
    assert main(["cut", str(low), "--rpm", "6500", "--teeth", "2", "--rpm-tolerance", "0.05",
                 "--out", str(tmp_path / "c.json")]) == 0
    assert "note.opus: warning: coded as Opus at" in capsys.readouterr().err
    assert json.loads((tmp_path / "c.json").read_text())["record_warnings"] == list(said)


def test_talk_during_a_stable_cut_that_reads_as_chatter_is_warned_of():
    """Talk during the cut at 0.3 × its RMS: a voice's harmonic passes every chatter test (11 of 30 stable records
    of ``shop_synth`` called chatter with eSpeak NG's sentences). It glides, and chatter's frequency holds — but heavy
    simulated chatter steps as it saturates (17 right verdicts of 2 752 lost as a veto), so it is said, not judged:
    each stable cut so called chatter is warned of, and no chattering cut with talk over it, nor without."""
    import soundfile as sf
    from scipy.signal import resample_poly

    talks = [resample_poly(sf.read(TALK / f"talk_{k}.flac")[0], 2, 1) for k in "abc"]
    warned = 0
    for rpm, teeth, chatter, seed in [(15000, 2, None, 6), (12000, 4, None, 8), (6000, 4, 1234.0, 1),
                                      (9000, 3, 2345.0, 3)]:
        x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, chatter_hz=chatter, chatter_amp=0.5, air_s=2.0,
                                      cut_s=7.0, seed=seed)
        rms = np.sqrt(np.mean(x[int(t0 * rate):int(t1 * rate)] ** 2))
        plain = analyse_cut(x / 1.5, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
        assert not any("does not hold its frequency" in w for w in plain.criterion["warnings"])
        for v in talks:
            y = x.copy()
            i = int((t0 + 0.5) * rate)
            y[i:i + v.size] += 0.3 * rms * v / np.sqrt(np.mean(v ** 2))
            res = analyse_cut(y / 1.5, rate, rpm=rpm, teeth=teeth, full_scale=1.0)
            said = [w for w in res.criterion["warnings"] if "does not hold its frequency" in w]
            if chatter is not None:
                assert res.verdict == "chatter" and abs(res.chatter_hz / chatter - 1) < 0.01 and not said
            elif res.verdict == "chatter":
                assert len(said) == 1 and f"{res.chatter_hz:.1f} Hz" in said[0], res.chatter_hz
                warned += 1
    assert warned >= 2
