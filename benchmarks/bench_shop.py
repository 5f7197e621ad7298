"""Test cuts: ``cut`` speed and accuracy, ``update`` convergence over virtual campaigns (prints; not a test).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_shop.py [--seeds 20] [--quick]
        [--only cut|teeth|recorder|twocut|inside|update|sampler|forward|ceiling|sdm-bands|heard|bracket|prior-pocket|
                exact]
        [--shops zoa,noisy,sdm,sim]
        [--cases cornelius,example]
        [--max-cuts 10] [--verbose] [--no-stop]
        [--update '{"n_samples": 500, "lobe_samples": 200, "forward": "sdm"}'] [--cut-truth-seed 20] [--seed-level 0.01]
        [--sensor microphone|accelerometer]

Prints the machine, date and load first; per case and shop the median cuts to converge, the fraction converged,
the median (max) chattering cuts and the CPU per update (median, max); ``--verbose`` one line per seed.

CPU time (time.process_time), not wall time: the machine is shared.

1. ``cut``: CPU per second of 44.1 kHz audio on the real shop recording (examples/cuts) and on synthetic shop
   records (tests/shop_synth.py); verdicts over a (speed, chatter amplitude) grid of synthetic records; verdicts
   against the SDM on cuts simulated by toolpoint.simulation over a random (speed, depth) grid and at pocket
   speeds, heard by the tests' shop microphone or (``--sensor accelerometer``) by an accelerometer on the spindle
   housing (tests/milling_sim.py: force through a housing mode, bearing and imbalance lines, mains hum, offset and
   drift, 25.6 kS/s).
   ``teeth``: the same simulated records judged with a wrong tooth count (N ± 1, 2 N, N / 2): the verdicts it
   changes and whether ``cut`` warns of the count, and the records warned at the right count.
   ``recorder``: the same records started 50 ms later, stopped 50 ms earlier, 30 dB quieter, with offset and drift,
   with 3 s more air (a microphone's also in 16 bits 30 dB down, at 48 kHz, through MP3): the verdicts each moves.
   ``twocut``: two of those records one after the other, at one speed (two depths: neither refused nor judged
   worse) or at two speeds ×1.31 apart (refused: one ``--rpm`` judges one speed).
   ``inside``: records taken inside a chattering cut, without air cut (windows of the real recording's chattering
   stretch; synthetic cuts whose chatter waxes and wanes).
2. ``update``: virtual campaigns (truth drawn from the prior, the next cut from the ``info`` rule) on the
   Cornelius et al. 2024 two-mode case and on the toolpoint example tool, over ``--seeds`` seeds, with the shops
   ``zoa`` (cuts labelled by the true zero-order limit: the update's own model), ``noisy`` (the true limit
   blurred by 3 % per cut, chatter frequency measured to 0.5 %), ``sdm`` (the same with the truth's SDM limit and
   chatter frequency: the whole loop's truth without the simulation and the detector — with ``--update
   '{"label_offset": [0, 0], "label_growth": [0, 0]}'`` the labels follow the likelihood's model (their 3 % blur
   within its 5 % boundary width), a check of the SDM forward path's calibration) and ``sim`` (each cut
   simulated in the time domain by toolpoint.simulation (``simulated_shop``), heard by the tests' shop microphone
   (tests/milling_sim.py: fans, spindle lines, room noise, air cut), judged by
   ``analyse_cut``: the whole loop). Targets: ≤ 6 cuts (median) until the 5–95 %
   band holds the true limit at ≥ 90 % of the speeds and is ≤ 20 % of the limit wide at the recommended speed;
   ≤ 1 chattering cut (median); each update ≤ 30 s CPU. SMC against SIR (ESS at equal CPU) on one case.
   With ``--no-stop``, after each number of cuts: the band's mean coverage over the truths with its standard error
   (a truth's coverage is one draw: its speeds are not independent; ±0.02–0.05 over 20 truths), and its change from
   the prior's band paired by truth; the P(stable) map's P(chatter) at the truth's own limit (the share of speeds at
   or under 0.05 … 0.95: the same numbers where the map is calibrated); the share of truths whose parameters the
   printed 5–95 % ranges held; and, over all the campaigns, each proposed cut's claimed P(chatter) against the chatter
   heard and its depth over the true limit.
3. ``forward``: CPU of one call of the likelihood's forward model (``limit_at_speeds``, 500 samples, 6 speeds).
4. ``ceiling``: what the convergence test asks of an exactly calibrated band. The prior's own 5–95 % band
   (zero-order lobes of ``lobe_samples`` prior samples) against 1000 truths drawn from the same prior: the mean
   share of speeds where the truth lies in the band (≈ 0.90 when calibrated) and the share of truths for which it
   is ≥ 0.90 — the most a campaign's coverage test can pass at one update when the posterior is exact (a
   posterior given the cuts holds a truth drawn from the prior like the prior holds it, on average over truths).
   First the label offset's floor: the 5–95 % range of δ + min(G / (κ t), 0.5) under ``update``'s priors, for
   growth rates κ and cut durations t — the narrowest band that heard labels bracketing the limit at one speed leave.
5. ``sdm-bands``: the ``forward="sdm"`` band against the truth's own SDM limit at a cut speed and at a random
   speed (Cornelius σ 0.12, 40 truths, three cuts each, lobe grids of 41 and 21 speeds).
6. ``heard``: what decides whether the whole loop's shop hears a cut past the limit as chatter — the label against
   the zero-order κ x, the SDM's secant κ x and the SDM's own growth at the cut's depth, each times the cut's duration,
   fitted as P(heard) = Φ((ln(g t) − ln G) / s) (truths from the prior, cuts 0–25 % past the SDM limit, 0.9–4 s).
7. ``bracket`` (``--seeds`` truths from ``--seed-start``): the band ``update`` leaves after cuts that bracket each
   truth's SDM limit at one speed exactly (no simulation, no detector: an oracle's labels), with the label model and
   with exact labels — the floor the label offset sets on the loop's width target, however well the cuts are placed.
8. ``prior-pocket``: the prior's band (``update`` with no cut) near its recommended speed, where the first cuts go,
   against the SDM limits of 400 truths drawn from the prior: the share below its 5 % and above its 95 % line; and
   the truths' SDM limits' 5–95 % range there against their zero-order limits' (the whole loop's prior width against
   the zero-order shop's).
9. ``exact`` (only when asked; ``--seeds`` truths from ``--seed-start``, ``--cases``): ``update``'s SDM-path
   posterior against an exact-likelihood SMC (each sample's own SDM limit at the cut speeds) on the ``sdm`` shop with
   δ = G = 0 — what its approximations cost in coverage, against the 0.90 an exact posterior holds on average.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from milling_sim import accelerometer, microphone  # noqa: E402
from shop_synth import shop_record  # noqa: E402

from toolpoint.io.records import read_cut_record  # noqa: E402
from toolpoint.shop import analyse_cut  # noqa: E402
from toolpoint.shop.campaign import sdm_limit, simulated_shop, virtual_campaign  # noqa: E402
from toolpoint.shop.model import cornelius_2024, example_tool, limit_at_speeds  # noqa: E402
from toolpoint.shop.update import TestCut, update  # noqa: E402

REAL = Path(__file__).resolve().parents[1] / "examples" / "cuts" / "combined_chatter6567.mp3"


def _cpu() -> str:
    """The CPU model and its widest vector extension: CPU seconds differ 2–4× between the VMs this ran on (an AMD
    EPYC without AVX-512 took 0.37 s for what took 0.11 s the session before)."""
    try:
        info = open("/proc/cpuinfo").read()
        model = next(ln.split(":", 1)[1].strip() for ln in info.splitlines() if ln.startswith("model name"))
        flags = next(ln.split(":", 1)[1].split() for ln in info.splitlines() if ln.startswith("flags"))
        return model + (", AVX-512" if "avx512f" in flags else ", AVX2" if "avx2" in flags else "")
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def header():
    from toolpoint.memory import keep_freed_memory

    kept = keep_freed_memory()  # as the toolpoint command does on start (toolpoint.memory)
    when = time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())
    print(f"# {platform.node()} {platform.machine()} ({_cpu()}, {os.cpu_count()} cores), numpy {np.__version__}, "
          f"{when}, load average {os.getloadavg()[0]:.2f}; CPU seconds (process_time), OMP_NUM_THREADS="
          f"{os.environ.get('OMP_NUM_THREADS', 'unset')}; freed memory kept (toolpoint.memory): {kept}")


def bench_cut(quick):
    print("\n## cut")
    rec = read_cut_record(REAL)
    t = time.process_time()
    res = analyse_cut(rec.samples, rec.rate_hz, rpm=6500, teeth=2, rpm_tolerance=0.05, full_scale=1.0)
    cpu = time.process_time() - t
    print(f"real recording {rec.duration_s:.1f} s: {cpu:.2f} s CPU = {cpu / rec.duration_s:.3f} s per s of audio; "
          f"verdict {res.verdict} at {res.chatter_hz:.1f} Hz; spindle {res.rpm:.1f} rpm")
    for s in res.segments:
        print(f"   {s.kind:6s} {s.start_s:6.2f}-{s.end_s:6.2f} s  {s.verdict:9s} "
              f"{'' if s.chatter_hz is None else format(s.chatter_hz, '.1f')}")
    ok = n = at_alias = 0
    fe = []
    cpu_total = dur_total = 0.0
    rng = np.random.default_rng(0)
    speeds = np.linspace(3000, 15000, 4 if quick else 8)
    amps = (0.0, 0.3, 0.5, 1.0)
    for rpm in speeds:
        for amp in amps:
            teeth = int(rng.integers(2, 5))
            fc = float(rng.uniform(500, 3500))
            x, rate, *_ = shop_record(rpm=rpm, teeth=teeth, chatter_hz=fc if amp else None, chatter_amp=amp,
                                      fans=tuple(rng.uniform(300, 4000, 2)), seed=int(rng.integers(1 << 30)))
            t = time.process_time()
            r = analyse_cut(x, rate, rpm=rpm * rng.uniform(0.98, 1.02), teeth=teeth, full_scale=1.0)
            cpu_total += time.process_time() - t
            dur_total += x.size / rate
            want = "chatter" if amp else "stable"
            n += 1
            ok += r.verdict == want
            if amp and r.chatter_hz:
                fam = fc + teeth * r.rpm / 60 * np.arange(-2, 3)  # the record's chatter lines: f_c and its aliases
                j = int(np.argmin(np.abs(r.chatter_hz - fam)))
                fe.append(abs(r.chatter_hz / fam[j] - 1))
                at_alias += j != 2
    print(f"synthetic shop records: {ok}/{n} verdicts right (chatter amplitude 0, 0.3, 0.5, 1 of the first tooth "
          f"harmonic's), chatter frequency error (to the nearest line of f_c + j f_t) median {np.median(fe):.2%} max "
          f"{np.max(fe):.2%}, {at_alias} of {len(fe)} found at an alias (f_c under a spindle harmonic); "
          f"{cpu_total / dur_total:.3f} s CPU per s of audio")
    # stable cuts with a stray tone that starts with the cut (a feed drive, a pump): the alias rule's risk
    fa = {0.0: 0, 0.002: 0}
    n = 0
    for _ in range(10 if quick else 40):
        rpm, teeth = float(rng.uniform(3000, 15000)), int(rng.integers(2, 5))
        x, rate, t0, t1 = shop_record(rpm=rpm, teeth=teeth, fans=tuple(rng.uniform(300, 4000, 2)),
                                      seed=int(rng.integers(1 << 30)))
        t = np.arange(x.size) / rate
        on = np.clip((t - t0) / 0.05, 0, 1) * np.clip((t1 - t) / 0.05, 0, 1)
        tone = float(rng.uniform(300, 4000))
        x = x + rng.uniform(0.01, 0.05) * on * np.sin(2 * np.pi * tone * t)  # ~0.2–4 % of the harmonic in power
        n += 1
        for ad in fa:
            r = analyse_cut(x, rate, rpm=rpm, teeth=teeth, full_scale=1.0, alias_dominance=ad)
            fa[ad] += r.verdict == "chatter"
    print(f"stable synthetic records with a stray tone switched on with the cut (300–4000 Hz, 0.01–0.05 of full "
          f"scale): false chatter {fa[0.002]}/{n} with the alias rule (alias_dominance 0.002), {fa[0.0]}/{n} without")


def bench_cut_inside(quick):
    """Records taken inside a chattering cut (no air cut): windows of the real recording's chattering stretch under
    two readings of its speed and teeth, and synthetic cuts without air whose chatter waxes and wanes."""
    print("\n## cut: records inside the cut (no air cut)")
    rec = read_cut_record(REAL)
    x, rate = rec.samples, rec.rate_hz
    starts = np.arange(9.6, 14.01, 0.4 if quick else 0.2)
    for kw in (dict(rpm=6500, teeth=2, rpm_tolerance=0.05), dict(rpm=6460, teeth=4)):
        n = ok = 0
        for a in starts:
            for d in (2, 3, 4, 5, 6):
                if a + d > 16.1:
                    continue
                r = analyse_cut(x[int(a * rate):int((a + d) * rate)], rate, full_scale=rec.full_scale, **kw)
                n += 1
                ok += r.verdict == "chatter" and abs(r.chatter_hz / 1067.3 - 1) < 0.01
        print(f"real recording, windows of 2–6 s starting {starts[0]:.1f}–{starts[-1]:.1f} s inside its chattering "
              f"stretch, {kw['rpm']} rpm and {kw['teeth']} teeth given: {ok}/{n} chatter at 1067.3 Hz ±1 %")
    combos = ((6000, 4, 1234.0), (9000, 3, 1630.0), (12000, 2, 2890.0), (3000, 4, 731.0), (18000, 6, 2345.0))
    n = ok = 0
    for seed in range(1 if quick else 3):
        for rpm, teeth, fc in combos:
            for chatter in (None, fc):
                for swing in (0.0, 10.0, 16.0):
                    for amp in ((0.5, 2.0, 5.0) if chatter else (0.5,)):
                        y, rate_y, *_ = shop_record(rpm=rpm, teeth=teeth, chatter_hz=chatter, chatter_amp=amp,
                                                    mode_hz=fc, air_s=0.0, cut_s=5.0, chatter_swing_db=swing,
                                                    fans=(), seed=seed)
                        r = analyse_cut(y, rate_y, rpm=rpm, teeth=teeth, full_scale=1.0)
                        n += 1
                        ok += (r.verdict == "stable" if chatter is None else
                               r.verdict == "chatter" and abs(r.chatter_hz / fc - 1) < 0.01)
    print(f"synthetic cuts without air (tests/shop_synth.py: 5 speeds and tooth counts, chatter 0.5–5 x the tooth-"
          f"passing line waxing and waning by 0, 10, 16 dB, stable ones, no fans): {ok}/{n} right")


# (dominance, alias_dominance, growth_db): the default first; without the growth test; its rise at 3 and 10 dB;
# the alias rule's default before 2026-11-26 (0.005); lower ratios
THRESHOLDS = ((0.05, 0.002, 6.0), (0.05, 0.002, 0.0), (0.05, 0.002, 3.0), (0.05, 0.002, 10.0), (0.05, 0.005, 6.0),
              (0.05, 0.001, 6.0), (0.001, 0.0001, 6.0))


class _Score:
    """Verdicts of ``cut`` on simulated records against the SDM (and the simulation's own verdict), per threshold."""

    def __init__(self, record=None, force_noise=0.0):
        self.record = record or shop_microphone  # the sensor: (res, rpm, teeth, rng, point) -> (samples, rate)
        self.force_noise = force_noise  # the simulation's relative cutting-force noise
        self.full_scale = 1.0 if self.record is shop_microphone else None  # a sound file's full scale; a DAQ's in m/s²
        self.right = dict.fromkeys(THRESHOLDS, 0)
        self.right_sim = dict.fromkeys(THRESHOLDS, 0)
        self.false_alarm = dict.fromkeys(THRESHOLDS, 0)
        self.n = self.skipped = self.sim_agree = 0
        self.refused = dict.fromkeys(THRESHOLDS, 0)  # refused in one line (InputError): counted as not right
        self.ferr, self.cpu_cut, self.audio_s = [], 0.0, 0.0

    def heard(self, mm, c, rpm, depth, lim, seed, seed_level, rng):
        """(the simulation of the points (rpm, depth), {point: (samples, rate)}): each point not within ±5 % of its
        SDM limit ``lim`` heard by ``self.record`` (the others counted in ``skipped``), in the points' order."""
        from toolpoint.simulation import simulate_milling

        res = simulate_milling(mm, mm, c, rpm=rpm, depth_m=depth, revolutions=250, seed=seed, seed_level=seed_level,
                               force_noise=self.force_noise)
        recs = {}
        for p in range(rpm.size):
            if abs(depth[p] / lim[p] - 1) < 0.05:
                self.skipped += 1
                continue
            recs[p] = self.record(res, float(rpm[p]), c.teeth, rng, point=p)
        return res, recs

    def add(self, mm, c, rpm, depth, lim, rho, seed, seed_level, rng):
        """Simulate the points (rpm, depth) (their SDM limit ``lim`` and ρ), hear and judge them."""
        from toolpoint.errors import InputError

        res, recs = self.heard(mm, c, rpm, depth, lim, seed, seed_level, rng)
        for p, (x, rate) in recs.items():
            chatter = bool(rho[p] > 1)
            self.n += 1
            self.sim_agree += chatter == (not res.stable[p])
            for thr in THRESHOLDS:
                t0 = time.process_time()
                try:
                    r = analyse_cut(x, rate, rpm=float(rpm[p]), teeth=c.teeth, full_scale=self.full_scale,
                                    dominance=thr[0], alias_dominance=thr[1], growth_db=thr[2])
                except InputError as e:  # e.g. a housing accelerometer that does not hear the spindle
                    self.refused[thr] += 1
                    if thr == THRESHOLDS[0]:
                        print(f"   refused: {float(rpm[p]):.0f} rpm, {float(depth[p] / lim[p]):.2f} × the limit, "
                              f"truth seed {seed}: {e}", flush=True)
                    continue
                if thr == THRESHOLDS[0]:
                    self.cpu_cut += time.process_time() - t0
                    self.audio_s += x.size / rate
                    if chatter and r.chatter_hz and np.isfinite(res.chatter_hz[p]):
                        alias = res.chatter_hz[p] + c.teeth * rpm[p] / 60 * np.arange(-3, 4)
                        self.ferr.append(float(np.min(np.abs(r.chatter_hz - alias)) / r.chatter_hz))
                self.right[thr] += (r.verdict == "chatter") == chatter
                self.right_sim[thr] += (r.verdict == "chatter") == (not res.stable[p])
                self.false_alarm[thr] += r.verdict == "chatter" and not chatter

    def report(self, what):
        n = self.n
        print(f"{what}; {self.skipped} within ±5 % of the SDM limit left out; the simulation agrees with the SDM on "
              f"{self.sim_agree}/{n}):")
        for thr in THRESHOLDS:
            print(f"   dominance {thr[0]:g}, with an alias {thr[1]:g}, growth {thr[2]:g} dB"
                  f"{' (default)' if thr == THRESHOLDS[0] else ''}: "
                  f"{self.right[thr]}/{n} verdicts right "
                  f"({self.right[thr] / n:.1%}), {self.false_alarm[thr]} false chatter"
                  f"{f', {self.refused[thr]} refused' if self.refused[thr] else ''}; against the simulation's own "
                  f"verdict {self.right_sim[thr]}/{n} ({self.right_sim[thr] / n:.1%})")
        ferr = np.array(self.ferr)
        print(f"   chatter frequency (modulo tooth-passing aliases) vs the simulation's: median {np.median(ferr):.2%}, "
              f"{np.mean(ferr < 0.01):.0%} within 1 % (n {ferr.size}); cut {self.cpu_cut / self.audio_s:.3f} s CPU "
              f"per s of audio")


class _TeethScore(_Score):
    """What a wrong tooth count does to ``cut`` on the same records, and whether it is warned.

    Each record is judged with its tooth count N and with N − 1, N + 1, 2 N and N / 2 (even N); per kind of slip: the
    records whose verdict it changed (and to chatter), those of them warned ("the spindle harmonics that stand out
    in the …"), and all warned; for N itself, the records warned (false warnings)."""

    KINDS = ("right", "N-1", "N+1", "2N", "N/2")

    def __init__(self, record=None):
        super().__init__(record)
        self.count = {k: dict.fromkeys(("n", "refused", "changed", "to_chatter", "changed_warned", "warned"), 0)
                      for k in self.KINDS}

    def add(self, mm, c, rpm, depth, lim, rho, seed, seed_level, rng):
        from toolpoint.errors import InputError

        _, recs = self.heard(mm, c, rpm, depth, lim, seed, seed_level, rng)
        n_t = c.teeth
        for p, (x, rate) in recs.items():
            self.n += 1
            ref = analyse_cut(x, rate, rpm=float(rpm[p]), teeth=n_t, full_scale=self.full_scale)
            slips = {"right": n_t, "N-1": n_t - 1, "N+1": n_t + 1, "2N": 2 * n_t,
                     "N/2": n_t // 2 if n_t % 2 == 0 else 0}
            for kind, z in slips.items():
                if z < 1:
                    continue
                cnt = self.count[kind]
                cnt["n"] += 1
                try:
                    r = ref if kind == "right" else analyse_cut(x, rate, rpm=float(rpm[p]), teeth=z,
                                                                full_scale=self.full_scale)
                except InputError:  # 2 N's fourth tooth harmonic above Nyquist
                    cnt["refused"] += 1
                    continue
                warned = any("spindle harmonics that stand out in the" in w for w in r.criterion["warnings"])
                changed = r.verdict != ref.verdict
                cnt["changed"] += changed
                cnt["to_chatter"] += changed and r.verdict == "chatter"
                cnt["changed_warned"] += changed and warned
                cnt["warned"] += warned

    def report(self, what):
        print(f"{what}; {self.skipped} within ±5 % of the SDM limit left out), each judged with a wrong tooth count:")
        for kind, cnt in self.count.items():
            if kind == "right":
                print(f"   N (right): {cnt['n']} records, {cnt['warned']} warned of their tooth count")
                continue
            print(f"   {kind}: {cnt['n']} records ({cnt['refused']} refused): verdict changed {cnt['changed']} "
                  f"({cnt['to_chatter']} to chatter), of them warned {cnt['changed_warned']}; warned in all "
                  f"{cnt['warned']}")


class _RecorderScore(_Score):
    """What the way a record was taken does to ``cut``: each record judged as heard and after a change that should
    not matter — started 50 ms later (``later``) or stopped 50 ms earlier (``earlier``): the first or last samples
    cut off; 30 dB quieter (``quiet``); a DC offset of 0.05 full scale with drifts at 0.3 Hz and 7 Hz (``drift``);
    3 s more air before the cut, the record's own (``air``: 0.5 s of it from 0.05 s on, every other copy reversed
    so that nothing jumps); a sound file's also 30 dB quieter in 16 bits (``quiet 16-bit``), resampled to 48 kHz
    (``48 kHz``) and through libsndfile's MP3 encoder at its default bit rate (``MP3``). Per change: the records
    whose verdict moved (to chatter), refused, and the verdicts right against the SDM; see ``docs/design/shop.md``,
    *A short air cut at the record's start or end*."""

    KINDS = ("as heard", "later", "earlier", "quiet", "drift", "air")
    AUDIO = ("quiet 16-bit", "48 kHz", "MP3")  # a sound file's (full scale 1), not a DAQ's record in m/s²

    def __init__(self, record=None):
        super().__init__(record)
        self.kinds = self.KINDS + (self.AUDIO if self.full_scale == 1.0 else ())
        self.count = {k: dict.fromkeys(("n", "refused", "changed", "to_chatter", "right"), 0) for k in self.kinds}

    @staticmethod
    def changed(kind, x, rate):
        """(the record as ``kind`` takes it, its rate Hz)."""
        k = int(0.05 * rate)
        if kind == "later":
            return x[k:], rate
        if kind == "earlier":
            return x[:x.size - k], rate
        if kind == "quiet":
            return x * 10 ** (-30 / 20), rate
        if kind == "drift":
            t = np.arange(x.size) / rate
            y = x + 0.05 + 0.05 * np.sin(2 * np.pi * 0.3 * t) + 0.02 * np.sin(2 * np.pi * 7 * t)
            return y / max(1.0, float(np.abs(y).max()) / 0.99), rate
        if kind == "air":
            air = x[k:k + int(0.5 * rate)]
            return np.concatenate([air if j % 2 == 0 else air[::-1] for j in range(6)] + [x]), rate
        if kind == "quiet 16-bit":
            return np.round(x * 10 ** (-30 / 20) * 32767) / 32767, rate
        if kind == "48 kHz":
            from fractions import Fraction

            from scipy.signal import resample_poly

            q = Fraction(48000, int(round(rate)))
            return resample_poly(x, q.numerator, q.denominator), 48000.0
        if kind == "MP3":
            import io

            import soundfile as sf

            buf = io.BytesIO()
            sf.write(buf, np.clip(x, -1.0, 1.0), int(round(rate)), format="MP3")
            buf.seek(0)
            y, r = sf.read(buf)
            return y, float(r)
        return x, rate

    def add(self, mm, c, rpm, depth, lim, rho, seed, seed_level, rng):
        from toolpoint.errors import InputError

        _, recs = self.heard(mm, c, rpm, depth, lim, seed, seed_level, rng)
        for p, (x, rate) in recs.items():
            self.n += 1
            chatter = bool(rho[p] > 1)
            ref = None
            for kind in self.kinds:
                cnt = self.count[kind]
                cnt["n"] += 1
                y, r_y = self.changed(kind, x, rate)
                try:
                    r = analyse_cut(y, r_y, rpm=float(rpm[p]), teeth=c.teeth, full_scale=self.full_scale)
                except InputError:
                    cnt["refused"] += 1
                    continue
                ref = r.verdict if kind == "as heard" else ref
                moved = ref is not None and r.verdict != ref
                cnt["changed"] += moved
                cnt["to_chatter"] += moved and r.verdict == "chatter"
                cnt["right"] += (r.verdict == "chatter") == chatter

    def report(self, what):
        print(f"{what}; {self.skipped} within ±5 % of the SDM limit left out), each judged as heard and as another "
              "recorder would have taken it:")
        for kind, cnt in self.count.items():
            print(f"   {kind}: {cnt['n']} records, {cnt['refused']} refused, verdict right {cnt['right']}"
                  + ("" if kind == "as heard" else
                     f", changed against as heard {cnt['changed']} ({cnt['to_chatter']} to chatter)"))


class _TwoCutScore(_Score):
    """Records that hold two cuts, each with its air cut (two simulated records one after the other).

    At one speed (consecutive depths of the grid): neither refused nor judged worse than its cuts — the verdict is
    right when it is chatter if either cut is past the SDM limit. At two speeds (consecutive speeds of the grid,
    ×1.31, one depth; judged at the first cut's speed): refused ("ran at another spindle speed"), not judged as one
    speed. Points within ±5 % of the SDM limit left out, as in the other scores."""

    def __init__(self, record=None):
        super().__init__(record)
        self.same = dict.fromkeys(("n", "refused", "right"), 0)
        self.two = dict.fromkeys(("n", "refused", "right"), 0)
        self.refusals = []

    def add(self, mm, c, rpm, depth, lim, rho, seed, seed_level, rng):
        from toolpoint.errors import InputError

        _, heard = self.heard(mm, c, rpm, depth, lim, seed, seed_level, rng)
        recs = {p: xr + (bool(rho[p] > 1),) for p, xr in heard.items()}
        n_s = np.unique(rpm).size
        pairs = []
        for p in recs:  # the grid is depths × speeds, raveled: p = i_depth * n_s + i_speed
            for q, kind in ((p + n_s, "same"), (p + 1, "two")):
                if q in recs and (kind == "same" or (p % n_s) + 1 < n_s):
                    pairs.append((p, q, kind))
        for p, q, kind in pairs:
            (x1, rate, c1), (x2, _, c2) = recs[p], recs[q]
            cnt = self.same if kind == "same" else self.two
            cnt["n"] += 1
            try:
                r = analyse_cut(np.concatenate([x1, x2]), rate, rpm=float(rpm[p]), teeth=c.teeth,
                                full_scale=self.full_scale)
            except InputError as e:
                cnt["refused"] += 1
                if kind == "same":
                    self.refusals.append(f"{rpm[p]:.0f} rpm, {1e3 * depth[p]:.3g} + {1e3 * depth[q]:.3g} mm: {e}")
                continue
            cnt["right"] += (r.verdict == "chatter") == (c1 or c2)

    def report(self, what):
        print(f"{what}; {self.skipped} within ±5 % of the SDM limit left out), two cuts in one record:")
        s, t = self.same, self.two
        print(f"   one speed, two depths: {s['n']} records, {s['refused']} refused, verdict right {s['right']} "
              f"(chatter if either cut is past the limit)")
        for line in self.refusals:
            print(f"      refused: {line}")
        print(f"   two speeds (x1.31), one depth: {t['n']} records, {t['refused']} refused; of the rest "
              f"{t['right']} judged right")


def _truth(pr, rng, random_cut=True):
    """A truth θ* drawn from the prior: (ModalModel, CuttingConditions), with a random immersion and direction
    unless ``random_cut`` is false (the prior's own)."""
    import dataclasses

    mm, c = pr.tool(pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None, :])[0])
    if not random_cut:
        return mm, c
    return mm, dataclasses.replace(c, radial_immersion=float(rng.choice([0.1, 0.25, 0.5, 1.0])),
                                   milling=str(rng.choice(["down", "up"])))


def bench_cut_sim(quick, truths=6, seed_start=10, seed_level=0.01, sensor="microphone", score=None, force_noise=0.0):
    """Verdicts of ``cut`` on records (``sensor``) of cuts simulated by ``toolpoint.simulation``; truth: the SDM.

    Each simulated cut starts on the steady cut with a kick of ``seed_level`` × the forced response (a shop cut's
    modes are excited by the entry and the cutting noise; the simulation's own default, 1e-6, only measures the
    linear growth, and a cut barely past the limit has not chattered audibly by the end of the record).
    Truths drawn from the Cornelius et al. 2024 prior (σ 0.1) and the example tool's (σ 0.15), seeds
    ``seed_start``…, each
    with a random radial immersion (0.1/0.25/0.5/1) and up/down milling; 7 speeds (5000–25000 rpm) × 7 depths
    (0.2–3 × the median SDM limit), 250 revolutions from the steady cut, heard by tests/milling_sim.py's
    microphone (room noise, fans, spindle lines) or its housing accelerometer (``sensor="accelerometer"``). Points
    within ±5 % of the SDM limit left out.
    """
    from toolpoint.stability import sdm_lobes, sdm_spectral_radius

    sc = score or _Score(SENSORS[sensor], force_noise)  # or another scorer of the same records (_TeethScore)
    for case in ("cornelius", "example"):
        for seed in range(seed_start, seed_start + (2 if quick else truths)):
            rng = np.random.default_rng(seed)
            pr = {"cornelius": cornelius_2024(0.1), "example": example_tool(0.15)}[case]
            mm, c = _truth(pr, rng)
            speeds = np.geomspace(5000, 25000, 7)
            lim = sdm_lobes(mm, mm, c, rpm=speeds).depth_m
            depths = np.linspace(0.2, 3.0, 7) * np.median(lim)
            rho = sdm_spectral_radius(mm, mm, c, rpm=speeds[None, :], depth=depths[:, None])
            R, A = np.meshgrid(speeds, depths)
            sc.add(mm, c, R.ravel(), A.ravel(), np.broadcast_to(lim, R.shape).ravel(), rho.ravel(), seed, seed_level,
                   rng)
    sc.report(f"simulated {sensor} records (toolpoint.simulation, seed level {seed_level:g}, force noise "
              f"{force_noise:g}, "
              f"{2 * (2 if quick else truths)} random truths (seeds {seed_start}…) of the Cornelius and example-tool "
              f"priors, random immersion and up/down, 7 speeds x 7 depths")


def bench_cut_pockets(quick, priors, truths=4, seed_start=40, seed_level=0.01, sensor="microphone", score=None,
                      force_noise=0.0):
    """``cut`` at the speeds a chatter-avoiding choice lands on: a tooth-passing harmonic j f_t on a mode.

    For each truth (drawn from each prior, its immersion and direction, seeds
    ``seed_start``…) and each of its modes, the speeds 60 f_n / (N j) × (0.97, 1, 1.03), j = 1…4, inside the
    prior's speed range (else 5000–25000 rpm), at most 8 of them (the slowest dropped), and the depths (0.6, 0.8,
    1.15, 1.4, 2) × the SDM limit there. The grid of :func:`bench_cut_sim` samples speeds at random; the virtual
    campaigns' cuts sit in these pockets, where the resonant harmonic is 20–30 dB above the rest.
    """
    from toolpoint.shop.model import sdm_limits
    from toolpoint.stability import sdm_spectral_radius

    sc = score or _Score(SENSORS[sensor], force_noise)  # or another scorer of the same records (_TeethScore)
    for name, pr in priors.items():
        lo, hi = pr.rpm_range if pr.rpm_range is not None else (5000.0, 25000.0)
        for seed in range(seed_start, seed_start + (1 if quick else truths)):
            rng = np.random.default_rng(seed)
            th = pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None, :])[0]  # as _truth draws it
            mm, c = pr.tool(th)
            sp = (60 * np.asarray(mm.fn_hz)[:, None, None] / (c.teeth * np.arange(1, 5)[None, :, None])
                  * np.array([0.97, 1.0, 1.03])[None, None, :]).ravel()
            sp = np.sort(sp[(sp >= lo) & (sp <= hi)])[-8:]
            if sp.size == 0:
                continue
            lim = sdm_limits(pr, th, sp)[0]  # as deep as the pockets go (EM28-80's pass 100 × the minimum)
            ok = np.isfinite(lim)
            sp, lim = sp[ok], lim[ok]
            R = np.repeat(sp, 5)
            L = np.repeat(lim, 5)
            A = L * np.tile([0.6, 0.8, 1.15, 1.4, 2.0], sp.size)
            rho = sdm_spectral_radius(mm, mm, c, rpm=R, depth=A)
            sc.add(mm, c, R, A, L, rho, seed, seed_level, rng)
    sc.report(f"simulated {sensor} records at pocket speeds (force noise {force_noise:g}; a tooth-passing harmonic "
              f"on a mode; {', '.join(priors)}; "
              f"{1 if quick else truths} truths each, seeds {seed_start}…; 5 depths 0.6–2 × the SDM limit")


def noisy_shop(prior, rng_blur=0.03, f_noise=0.005):
    def shop(theta, rpm, depth, rng, duration_s=None):  # labels by a limit: no growth in time
        a, fc = limit_at_speeds(prior, theta[None, :], [rpm])
        stable = bool(depth < a[0, 0] * np.exp(rng.normal(0, rng_blur)))
        f_meas = None if stable else float(fc[0, 0] * (1 + rng.normal(0, f_noise)))
        return TestCut(float(rpm), float(depth), stable, f_meas)
    return shop


def sdm_shop(prior, rng_blur=0.03, f_noise=0.005):
    """Labels by the SDM limit of θ* at the cut's speed (its chatter frequency), blurred like :func:`noisy_shop`:
    the whole loop's forward model (the SDM truth) without the simulation and the detector."""
    from toolpoint.shop.model import sdm_limits

    def shop(theta, rpm, depth, rng, duration_s=None):  # labels by a limit: no growth in time
        lim, fc = sdm_limits(prior, theta, [float(rpm)])
        stable = bool(depth < lim[0] * np.exp(rng.normal(0, rng_blur)))
        f_meas = None if stable else float(fc[0] * (1 + rng.normal(0, f_noise)))
        return TestCut(float(rpm), float(depth), stable, f_meas)
    return shop


def shop_microphone(res, rpm, teeth, rng, point=0):
    """The tests' shop microphone (fans, spindle lines, pink room noise, air cut) of one simulated cut."""
    t = res.time_s[point] - res.time_s[point][0]
    d, f = res.displacement_m[point], res.force_n[point]
    x, rate, *_ = microphone((t, d[:, 0], d[:, 1], f[:, 0], f[:, 1]), rpm=rpm, teeth=teeth,
                             seed=int(rng.integers(1 << 30)))
    return x, rate


def shop_accelerometer(res, rpm, teeth, rng, point=0):
    """tests/milling_sim.py's accelerometer on the spindle housing (force through a housing mode, the tool's
    acceleration, bearing and imbalance lines, mains hum, offset and drift, sensor noise; 25.6 kS/s) of one cut."""
    t = res.time_s[point] - res.time_s[point][0]
    d, f = res.displacement_m[point], res.force_n[point]
    x, rate, *_ = accelerometer((t, d[:, 0], d[:, 1], f[:, 0], f[:, 1]), rpm=rpm, teeth=teeth,
                                seed=int(rng.integers(1 << 30)))
    return x, rate


SENSORS = {"microphone": shop_microphone, "accelerometer": shop_accelerometer}


def _priors(library_prior=None) -> dict:
    """The benchmark's priors by case name; ``library_prior`` OUT:TOOL adds "library", a tool of a `toolpoint library`
    output, its prior as `update --library` makes it."""
    priors = {"cornelius": cornelius_2024(0.1), "example": example_tool(0.15)}
    if library_prior:
        from toolpoint.shop.prior import prior_from_library

        out, tool = library_prior.rsplit(":", 1)
        priors["library"] = prior_from_library(out, tool)
    return priors


def bench_update(seeds, quick, shops=("zoa", "noisy", "sim"), cases=("cornelius", "example"), update_kw=None,
                 max_cuts=10, verbose=False, seed_start=0, library_prior=None, detector=None, stop=True,
                 sensor="microphone", force_noise=0.0):
    update_kw = dict(update_kw or {})
    n_s = update_kw.pop("n_samples", 600 if quick else 1000)
    n_l = update_kw.pop("lobe_samples", 300 if quick else 400)
    print(f"\n## update: virtual campaigns (info rule, SMC {n_s} samples, {n_l} lobe samples, {seeds} seeds "
          f"{seed_start}…{seed_start + seeds - 1}, at most {max_cuts} cuts; update options {update_kw or 'default'} "
          "(forward: zoa for the zoa and noisy shops unless given)"
          + (f"; detector options {detector}" if detector else "")
          + (f"; simulated cuts with force noise {force_noise:g}" if force_noise else "")
          + ("" if stop else "; no stop: every campaign makes all its cuts, convergence read from the same sequence")
          + ")")
    priors = _priors(library_prior)
    if library_prior:
        tool = library_prior.rsplit(":", 1)[1]
        print(f"library prior {tool}: modes {np.round(priors['library'].freq_hz, 0).tolist()} Hz, σ stiffness "
              f"{np.round(priors['library'].sigma_stiffness, 3).tolist()}, σ K_t {priors['library'].sigma_kt}, "
              f"σ K_r {priors['library'].sigma_kr}, rpm {priors['library'].rpm_range}")
    for case in cases:
        prior = priors[case]
        for shop_name in shops:
            conv, chat, over, cpu, fails, runs, rels = [], [], [], [], 0, [], []
            for seed in range(seed_start, seed_start + seeds):
                # a sound file's full scale is 1; an accelerometer's record is in m/s²
                det = detector if sensor == "microphone" else {"full_scale": None, **(detector or {})}
                shop = {"zoa": None, "noisy": noisy_shop(prior), "sdm": sdm_shop(prior),
                        "sim": simulated_shop(prior, record=SENSORS[sensor], detector=det,
                                              force_noise=force_noise)}[shop_name]
                truth = sdm_limit(prior) if shop_name in ("sim", "sdm") else None
                # the forward model of the shop's physics unless --update names one: the zero-order shops label by
                # the zero-order limit, the others by the SDM's (update's default, "sdm")
                fw = {"forward": "zoa"} if shop_name in ("zoa", "noisy") and "forward" not in update_kw else {}
                r = virtual_campaign(prior, rng=np.random.default_rng(seed), shop=shop, max_cuts=max_cuts,
                                     true_limit=truth, n_samples=n_s, lobe_samples=n_l, stop=stop, **fw, **update_kw)
                runs.append(r)
                conv.append(r.converged_after if r.converged_after is not None else np.inf)
                made = r.cuts if r.converged_after is None else r.cuts[:r.converged_after]
                chat.append(sum(not c.stable for c in made))
                # each cut's depth over the truth's limit at its speed (SDM for the time-domain shops, one speed a
                # call; alone a speed read 0.27 % above itself asked with neighbours, docs/design/stability.md): a
                # label of chatter below 1 is the detector's false chatter, a depth above 1 chatters physically
                # whatever it was heard as
                rel = [c.depth_m / float(np.ravel(truth(r.theta_true, [c.rpm]))[0]) if truth else
                       c.depth_m / float(limit_at_speeds(prior, r.theta_true[None, :], [c.rpm])[0][0, 0])
                       for c in r.cuts]
                over.append(sum(x > 1 for x in rel[:len(made)]))
                rels.append(rel)
                cpu.extend(r.update_cpu_s)
                fails += r.converged_after is None
                if verbose:
                    print(f"   seed {seed}: converged after {r.converged_after}, {chat[-1]} chattering;"
                          + f" {over[-1]} above the true limit; cuts "
                          + " ".join(f"{c.rpm:.0f}/{1e3 * c.depth_m:.2f}{'s' if c.stable else 'C'}"
                                     + f"<{x:.3f}>"
                                     + ("" if c.duration_s is None else f"({c.duration_s:.1f}s)")
                                     + ("" if c.growth_per_s is None else f"[σ {c.growth_per_s:.3g}/s]")
                                     for c, x in zip(r.cuts, rel))
                          + f"; width {np.round(r.width, 2).tolist()}; coverage {np.round(r.coverage, 2).tolist()}"
                          + (f"; missed below the 5 % / above the 95 % after the last {r.miss_low[-1]:.2f} / "
                             f"{r.miss_high[-1]:.2f}" if r.miss_low else "")
                          + ("; truth below the recommended depth after "
                             + ",".join(str(n) for n, b in enumerate(r.below_recommended) if b)
                             if any(r.below_recommended) else ""),
                          flush=True)
            conv = np.array(conv)
            p90 = np.sort(conv)[int(np.ceil(0.9 * conv.size)) - 1]  # inf where a tenth did not converge
            print(f"{prior.name[:40]:40s} shop {shop_name:5s}: cuts to converge median {np.median(conv):.1f} "
                  f"(p90 {p90:.1f}), converged {seeds - fails}/{seeds} within {max_cuts}; "
                  f"chattering cuts median {np.median(chat):.1f} (max {max(chat)}), above the true limit median "
                  f"{np.median(over):.1f} (max {max(over)}); CPU per update median "
                  f"{np.median(cpu):.1f} s, max {max(cpu):.1f} s", flush=True)
            if not stop:  # calibration after n cuts, over all the truths (none selected by a stop)
                for n in range(max_cuts + 1):
                    below = np.mean([r.below_recommended[n] for r in runs])
                    cov = np.array([r.coverage[n] for r in runs])
                    near = np.array([r.coverage_near[n] for r in runs])
                    away = np.array([r.coverage_away[n] for r in runs])
                    wid = np.median([r.width[n] for r in runs])
                    # the standard error over truths: a truth's coverage is one number (its speeds are not
                    # independent draws), and over 20 truths it was ±0.02–0.05; the change from the prior's band on
                    # the same truths (paired) takes out which truths the set happened to hold
                    se = cov.std(ddof=1) / math.sqrt(cov.size) if cov.size > 1 else float("nan")
                    d = cov - np.array([r.coverage[0] for r in runs])
                    se_d = d.std(ddof=1) / math.sqrt(d.size) if d.size > 1 else float("nan")
                    print(f"   after {n} cuts: truth below the recommended depth (claims 0.05) {below:.2f}; coverage "
                          f"mean {cov.mean():.3f} ± {se:.3f} (standard error over the truths; "
                          + ("" if n == 0 else
                             f"change from the prior's band, paired by truth, {d.mean():+.3f} ± {se_d:.3f}; ")
                          + f"truths ≥ 0.90: {np.mean(cov >= 0.9):.2f}), near the cuts (±3 %) "
                          + ("-" if np.all(np.isnan(near)) else f"{np.nanmean(near):.3f}")
                          + f", away {np.nanmean(away):.3f}; missed below the 5 % limit "
                          + f"{np.mean([r.miss_low[n] for r in runs]):.3f}, above the 95 % "
                          + f"{np.mean([r.miss_high[n] for r in runs]):.3f}; width at the recommended speed median "
                          + f"{wid:.2f}", flush=True)
                    # the P(stable) map at the truth's own limit: P(chatter) claimed there is uniform over truths and
                    # speeds where the map is calibrated (the share at or under x is x)
                    pits = [r.p_chatter_at_truth[n][np.isfinite(r.p_chatter_at_truth[n])] for r in runs]
                    sh = np.array([[np.mean(q <= x) if q.size else np.nan for x in _PIT_AT] for q in pits])
                    sh_se = np.nanstd(sh, axis=0, ddof=1) / math.sqrt(len(runs)) if len(runs) > 1 else sh[0] * np.nan
                    print("      map's P(chatter) at the truth's limit, share of speeds at or under "
                          + " / ".join(f"{x:g}" for x in _PIT_AT) + ": "
                          + " / ".join(f"{m:.3f}" for m in np.nanmean(sh, axis=0))
                          + " (± " + " / ".join(f"{e:.3f}" for e in sh_se) + ", standard error over the truths; "
                          + f"{sum(q.size for q in pits)} speeds)", flush=True)
                    _parameter_calibration(prior, runs, n)
                _next_cut_calibration(runs, rels)


_PIT_AT = (0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95)


def _parameter_calibration(prior, runs, n):
    """The printed 5–95 % range of each parameter after n cuts against the truth's value: the share of truths it
    held, and under / over it (0.90, 0.05 / 0.05 where calibrated; binomial sd ~0.07 over 20 truths)."""
    rank = np.array([r.parameter_rank[n] for r in runs])  # (truths, P)
    free = np.isfinite(rank).all(axis=0)
    lo, hi = rank < 0.05, rank > 0.95
    print("      parameters' 5–95 % range held the truth (under / over): "
          + "; ".join(f"{name} {1 - lo[:, k].mean() - hi[:, k].mean():.2f} "
                      f"({lo[:, k].mean():.2f}/{hi[:, k].mean():.2f})" for k, name in enumerate(prior.names) if free[k])
          + f"; all {1 - lo[:, free].mean() - hi[:, free].mean():.3f} ({lo[:, free].mean():.3f}/"
          + f"{hi[:, free].mean():.3f})", flush=True)


def _next_cut_calibration(runs, rels):
    """Each proposed cut's claimed P(chatter) against what it did: chatter heard, and its depth over the truth's
    limit (physical chatter), binned by the claim (a claim above the rule's risk is a step: ``next_cut["stepped"]``)."""
    p = np.array([q for r in runs for q in r.next_p_chatter])
    heard = np.array([not c.stable for r in runs for c in r.cuts])
    over = np.array([x > 1 for rel in rels for x in rel])
    print("      next cuts' claimed P(chatter) against the outcome (claimed mean; heard chatter; depth over the true "
          "limit), by claim:", flush=True)
    for lo, hi in ((0.0, 0.1), (0.1, 0.2), (0.2, 0.31), (0.31, 1.01)):
        k = (p >= lo) & (p < hi)
        if k.any():
            se = math.sqrt(max(p[k].mean() * (1 - p[k].mean()), 1e-12) / k.sum())
            print(f"        [{lo:.2f}, {min(hi, 1):.2f}): {k.sum():3d} cuts, claimed {p[k].mean():.3f} (binomial sd "
                  f"{se:.3f}); heard {heard[k].mean():.3f}; over the truth {over[k].mean():.3f}", flush=True)
    print(f"        all: {p.size} cuts, claimed {p.mean():.3f}; heard {heard.mean():.3f}; over the truth "
          f"{over.mean():.3f}", flush=True)


def bench_sampler():
    print("\n## sampler: SMC vs SIR on the Cornelius case, 6 cuts (truth = prior median × 1.15 in K_t⁻¹)")
    pr = cornelius_2024(0.1)
    truth = pr.theta(np.zeros((1, pr.sigma.size)))
    truth[0, 6] /= 1.15
    cuts = []
    for rpm, rel in ((20000, 0.8), (20000, 1.1), (14500, 0.9), (9000, 0.9), (20500, 0.95), (20500, 1.05)):
        a, fc = limit_at_speeds(pr, truth, [rpm])
        d = rel * a[0, 0]
        cuts.append(TestCut(float(rpm), float(d), bool(rel < 1), None if rel < 1 else float(fc[0, 0])))
    for method, n in (("smc", 1000), ("sir", 20000), ("sir", 100000)):
        t = time.process_time()
        # the zero-order model the sampler figures were measured with (cuts labelled by the zero-order limit)
        post = update(pr, cuts, rng=np.random.default_rng(0), method=method, n_samples=n, lobe_samples=400,
                      forward="zoa")
        cpu = time.process_time() - t
        j = int(np.argmin(np.abs(post.rpm - 20000)))
        uniq = len(np.unique(post.z[:, 6]))
        print(f"{method} {n:6d} samples: {cpu:5.1f} s CPU, ESS {[round(e) for e in post.ess]}, "
              f"distinct samples {uniq}, limit at 20000 rpm 5/50/95 % = {np.round(post.limit_q_m[:, j] * 1e3, 3)} mm")


def bench_forward():
    """CPU of the forward model the likelihood calls: ``limit_at_speeds`` of 500 prior samples at 6 speeds."""
    print("\n## forward model: limit_at_speeds, 500 prior samples × 6 speeds (CPU per call, best of 5)")
    for pr in (cornelius_2024(0.1), example_tool(0.15)):
        theta = pr.theta(np.random.default_rng(0).standard_normal((500, pr.sigma.size)) * (pr.sigma > 0))
        rpm = np.linspace(*pr.rpm_range, 6)
        cpu = []
        for _ in range(5):
            t = time.process_time()
            limit_at_speeds(pr, theta, rpm)
            cpu.append(time.process_time() - t)
        print(f"{pr.name[:40]:40s} {pr.freq_grid().size} frequencies, {pr.modes} modes: {min(cpu):.3f} s")


def bench_ceiling(cases, library_prior=None):
    from toolpoint.shop.update import _default_grid, _limits

    print("\n## ceiling: a calibrated band (the prior's own, zero-order) against 1000 truths from the same prior")
    priors = _priors(library_prior)
    # the label offset's own floor: however the cuts bracket the heard boundary at one speed, the limit lies the
    # offset δ + min(G / (κ t), 0.5) below it (update's label_offset and label_growth priors), so the band there is
    # at least as wide as that offset's 5–95 % range
    import inspect

    from toolpoint.shop.update import _GROWTH_CAP, update

    dflt = inspect.signature(update).parameters
    (mu, sd), (g_med, g_sd) = dflt["label_offset"].default, dflt["label_growth"].default
    rng = np.random.default_rng(0)
    d = mu + sd * rng.standard_normal(200_000)
    gg = g_med * np.exp(g_sd * rng.standard_normal(200_000))
    print(f"label offset δ ~ N({mu}, {sd}²), ln G ~ N(ln {g_med}, {g_sd}²): the 5–95 % width (ln) of "
          "δ + min(G / (κ t), 0.5), the narrowest band a bracket of heard labels at one speed leaves")
    for kap in (25.0, 30.0, 40.0, 100.0, 500.0):
        w = [np.subtract(*np.quantile(d + np.minimum(gg / (kap * t), _GROWTH_CAP), [0.95, 0.05]))
             for t in (0.85, 2.0, 3.0, 5.0)]
        print(f"   κ {kap:5.0f} /s: cuts of 0.85 / 2 / 3 / 5 s: " + " / ".join(f"{v:.3f}" for v in w), flush=True)
    for case in cases:
        pr = priors[case]
        f, g = pr.freq_grid(), _default_grid(pr)
        P, free = pr.sigma.size, pr.sigma > 0
        rng = np.random.default_rng(0)
        truth = _limits(pr, pr.theta(rng.standard_normal((1000, P)) * free), f, g)
        for m in (200, 400, 2000):
            q = np.quantile(_limits(pr, pr.theta(rng.standard_normal((m, P)) * free), f, g), [0.05, 0.95], axis=0)
            cov = ((q[0] <= truth) & (truth <= q[1])).mean(axis=1)
            print(f"{pr.name[:40]:40s} band of {m:4d} samples: mean coverage {cov.mean():.3f}, truths with "
                  f"coverage ≥ 0.90: {(cov >= 0.9).mean():.3f}, coverage 10/25/50 % "
                  f"{np.round(np.quantile(cov, [0.1, 0.25, 0.5]), 2).tolist()}", flush=True)


def bench_bracket(cases, library_prior=None, truths=8, seed_start=40, n_samples=1000, lobe_samples=400):
    """The band ``update`` leaves after cuts that bracket the truth's SDM limit at one speed exactly (an oracle:
    no simulation, no detector), with ``update``'s label model (the label offset δ and growth G it expects of a
    shop that hears chatter) and with exact labels (``label_offset`` and ``label_growth`` 0): how much of the band
    the label model keeps open, however well the cuts are placed."""
    from toolpoint.shop.update import TestCut

    print(f"\n## bracket: update's band after cuts bracketing the truth's SDM limit at the prior's recommended speed "
          f"(truths {seed_start}…{seed_start + truths - 1}, {n_samples} samples, {lobe_samples} lobe samples, cuts of "
          "1 s, no chatter frequency); width (a95 − a05) / a50 at that speed, [a05, a95] / the truth's limit")
    priors = _priors(library_prior)
    settings = {"label model": {}, "exact labels": {"label_offset": (0.0, 0.0), "label_growth": (0.0, 0.0)}}
    brackets = {"0.93 s / 1.07 C": ((0.93, True), (1.07, False)), "0.97 s / 1.03 C": ((0.97, True), (1.03, False)),
                "0.90 0.95 0.98 s / 1.02 1.05 1.10 C": ((0.9, True), (0.95, True), (0.98, True), (1.02, False),
                                                        (1.05, False), (1.1, False))}
    for case in cases:
        pr = priors[case]
        truth = sdm_limit(pr)
        widths: dict = {}
        for seed in range(seed_start, seed_start + truths):
            rng = np.random.default_rng(seed)  # the truth as virtual_campaign draws it from this seed
            th = pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None, :])[0]
            p0 = update(pr, [], rng=np.random.default_rng(1000 + seed), n_samples=n_samples,
                        lobe_samples=lobe_samples)
            r0 = p0.recommended["rpm"]
            lim = float(np.ravel(truth(th, [r0]))[0])
            line = []
            for bn, br in brackets.items():
                cuts = [TestCut(r0, f * lim, st, duration_s=1.0) for f, st in br]
                for sn, kw in settings.items():
                    q = update(pr, cuts, rng=np.random.default_rng(2000 + seed), n_samples=n_samples,
                               lobe_samples=lobe_samples, **kw).limit_q_m
                    j = int(np.argmin(np.abs(p0.rpm - r0)))
                    w = (q[2, j] - q[0, j]) / q[1, j]
                    widths.setdefault((bn, sn), []).append(w)
                    line.append(f"{w:.3f} [{q[0, j] / lim:.2f}, {q[2, j] / lim:.2f}]")
            print(f"   {pr.name[:24]} truth {seed}: {r0:.0f} rpm, limit {1e3 * lim:.3f} mm: " + "; ".join(line),
                  flush=True)
        for (bn, sn), w in widths.items():
            print(f"{pr.name[:40]:40s} {bn:36s} {sn:13s}: width median {np.median(w):.3f} (range "
                  f"{min(w):.3f}–{max(w):.3f})", flush=True)


def bench_heard(cases, library_prior=None, truths=12, seed_start=60):
    """What decides whether the whole loop's shop hears a cut past the limit as chatter: the label against three
    measures of how much chatter grew within the cut, ln(g t) — the zero-order κ times x = ln(a / a_SDM) (what
    ``update``'s label growth G / (κ t) assumes), the SDM's secant κ_SDM = ln ρ(1.05 a_SDM) / (T ln 1.05) times x, and
    the SDM's own growth at the cut's depth σ = ln ρ(a) / T (ρ the spectral radius per tooth period T) —, each fitted
    by P(heard) = ε + (1 − 2ε) Φ((ln(g t) − ln G) / s), ε = 0.01 (maximum likelihood). Truths from the prior, three
    speeds each in the upper half of its speed range, x ~ U(0, 0.25), the cut 250 revolutions, 2 s or 4 s long."""
    from scipy.optimize import minimize
    from scipy.special import log_ndtr

    from toolpoint.shop.model import growth_rate
    from toolpoint.stability import sdm_spectral_radius

    print(f"\n## heard: chatter heard against its growth within the cut ({truths} truths per case, 3 cuts each)")
    priors = _priors(library_prior)
    for case in cases:
        pr = priors[case]
        shop, truth = simulated_shop(pr, record=SENSORS["microphone"]), sdm_limit(pr)
        lo, hi = pr.rpm_range if pr.rpm_range is not None else (5000.0, 25000.0)
        rows = []
        c0 = time.process_time()
        for seed in range(seed_start, seed_start + truths):
            rng = np.random.default_rng(seed)
            th = pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None, :])[0]
            rpm = np.sort(rng.uniform(lo + 0.5 * (hi - lo), hi, 3))
            a_s = np.ravel(truth(th, rpm))
            _, fc = limit_at_speeds(pr, th[None, :], rpm)
            kz = growth_rate(pr, th[None, :], rpm, fc)[0]
            mm, cut = pr.tool(th)
            period = 60.0 / (rpm * cut.teeth)
            for i in np.flatnonzero(np.isfinite(a_s) & (a_s > 0)):
                x = rng.uniform(0.0, 0.25)
                dur = [None, 2.0, 4.0][rng.integers(3)]
                c = shop(th, rpm[i], a_s[i] * math.exp(x), rng, dur)
                r05, r_a = (float(np.ravel(sdm_spectral_radius(mm, mm, cut, rpm=[rpm[i]], depth=[d]))[0])
                            for d in (a_s[i] * 1.05, c.depth_m))
                # the chatter frequency read against the zero-order limiting lobe's and its tooth-passing aliases
                alias = fc[0, i] + cut.teeth * rpm[i] / 60.0 * np.arange(-2, 3)
                far = (float(np.min(np.abs(c.chatter_hz - alias))) / c.chatter_hz
                       if not c.stable and c.chatter_hz is not None else np.nan)
                rows.append((x, kz[i] * x, math.log(r05) / (period[i] * math.log(1.05)) * x,
                             math.log(r_a) / period[i], c.duration_s, not c.stable, far))
        R = np.array(rows, float)
        t, heard = R[:, 4], R[:, 5].astype(bool)
        ratio = R[:, 2] / R[:, 1]  # the SDM's secant κ over the zero-order κ at each cut
        print(f"{pr.name[:40]}: {len(R)} cuts 0–25 % past the SDM limit, {heard.sum()} heard as chatter; "
              f"κ_SDM / κ_ZOA at the cuts median {np.median(ratio):.2f}, 5–95 % "
              f"{np.quantile(ratio, 0.05):.2f}–{np.quantile(ratio, 0.95):.2f}, below 0.8 for "
              f"{np.mean(ratio < 0.8):.2f}, above 1.25 for {np.mean(ratio > 1.25):.2f}; "
              f"{time.process_time() - c0:.0f} s CPU", flush=True)
        far = R[np.isfinite(R[:, 6]), 6]
        print(f"   chatter frequency against the zero-order lobe's (nearest of f_c + j f_t, |j| ≤ 2), {far.size} "
              f"readings: within 0.5 % {np.sum(far <= 0.005)}, 2 % {np.sum(far <= 0.02)}, more than 10 % off "
              f"{np.sum(far > 0.1)}", flush=True)
        for name, col in (("zero-order κ x", 1), ("SDM secant κ x", 2), ("SDM σ at the depth", 3)):
            g = R[:, col] * t
            lg = np.log(np.where(g > 0, g, 1e-9))

            def nll(p, lg=lg):
                pc = 0.01 + 0.98 * np.exp(log_ndtr((lg - p[0]) / math.exp(p[1])))
                return -np.sum(np.where(heard, np.log(pc), np.log1p(-pc)))

            best = min((minimize(nll, [g0, math.log(0.5)], method="Nelder-Mead") for g0 in (0.0, 1.0, 2.0)),
                       key=lambda r: r.fun)
            print(f"   {name:20s}: G~ {math.exp(best.x[0]):.2f}, s {math.exp(best.x[1]):.2f}, −ln L {best.fun:.2f}; "
                  + "  ".join(f"{lab} " + (" ".join(f"{v:.1f}{'C' if h else 's'}" for v, h in
                                                   sorted(zip(g[m], heard[m]))) or "-")
                              for lab, m in (("≤1 s:", t <= 1.5), ("2 s:", (t > 1.5) & (t <= 3)), ("4 s:", t > 3))),
                  flush=True)


def bench_prior_pocket(cases, library_prior=None, truths=400, seed=123):
    """The prior's band (``update`` with no cut, ``forward="sdm"``, defaults) at the recommended speed and every third
    grid speed within ±3 % of it — where the first cuts go — against the SDM limits of ``truths`` tools drawn from
    the same prior (their own rng): the share below the band's 5 % and above its 95 % (each claims 0.05); and how
    widely the truths' SDM limits spread there against their zero-order limits (the whole loop's truth is the SDM's,
    the zero-order shop's the zero-order one: a wider spread is a wider prior for the cuts to narrow)."""
    from toolpoint.shop.model import sdm_limits

    print(f"\n## prior-pocket: the prior's 5-95 % band near the recommended speed against {truths} truths' SDM limits")
    priors = _priors(library_prior)
    for case in cases:
        pr = priors[case]
        c0 = time.process_time()
        post = update(pr, [], rng=np.random.default_rng(0))
        j = int(np.argmin(np.abs(post.rpm - post.recommended["rpm"])))
        sel = np.where(np.abs(post.rpm / post.rpm[j] - 1) <= 0.03)[0][::3]
        th = pr.theta(np.random.default_rng(seed).standard_normal((truths, pr.sigma.size)) * (pr.sigma > 0))
        lims = np.array([sdm_limits(pr, t, post.rpm[sel])[0] for t in th])  # (truths, speeds), m
        zoa = limit_at_speeds(pr, th, post.rpm[sel])[0]  # the same truths' zero-order limits
        q = post.limit_q_m[:, sel]
        tq = np.quantile(lims, [0.05, 0.5, 0.95], axis=0)
        zq = np.quantile(zoa, [0.05, 0.5, 0.95], axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            lr = np.log(lims / zoa)
        print(f"{pr.name[:40]:40s} recommended {post.recommended['rpm']:.0f} rpm; speeds "
              + " ".join(f"{r:.0f}" for r in post.rpm[sel]) + "; below the 5 %: "
              + " ".join(f"{v:.3f}" for v in (lims < q[0]).mean(0)) + "; above the 95 %: "
              + " ".join(f"{v:.3f}" for v in (lims > q[2]).mean(0)) + " (each claims 0.05); band 5/50/95 % "
              + " ".join("/".join(f"{1e3 * v:.2f}" for v in q[:, k]) for k in range(sel.size))
              + " mm; truths' " + " ".join("/".join(f"{1e3 * v:.2f}" for v in tq[:, k]) for k in range(sel.size))
              + " mm; the truths' 5-95 % range over their median, SDM limit / zero-order limit: "
              + " ".join(f"{(tq[2, k] - tq[0, k]) / tq[1, k]:.2f}/{(zq[2, k] - zq[0, k]) / zq[1, k]:.2f}"
                         for k in range(sel.size))
              + "; ln(SDM / zero-order) mean/sd " + " ".join(
                  f"{np.nanmean(lr[:, k]):.3f}/{np.nanstd(lr[:, k]):.3f}" for k in range(sel.size))
              + f"; {time.process_time() - c0:.0f} s CPU", flush=True)


def bench_exact(cases, library_prior=None, truths=20, seed_start=250, particles=400, band_samples=100):
    """``update``'s ``forward="sdm"`` posterior against an exact-likelihood one, on the ``sdm`` shop with the label
    model holding (δ = G = 0): each truth's campaign of six cuts without a stop, then the last update (its own seed)
    and a tempered SMC of ``particles`` samples whose likelihood takes each sample's own SDM limit at the cut speeds
    (``sdm_limit_near``'s default search, not a ratio of references or a fit) — the same labels, width, label noise
    and frequency term. Each band against the truth's SDM limit on every fifth speed of the grid: the reported band,
    and the 5–95 % range of ``band_samples`` samples' own SDM limits (the full search) of either posterior. A
    posterior exact under a likelihood that holds covers 0.90 on average over truths drawn from the prior — its band
    of n samples 0.9 (n − 1)/(n + 1), printed last; the paired difference says what ``update``'s approximations
    cost. Only with ``--only exact``: about 3 min CPU per truth."""
    from toolpoint.shop import update as U
    from toolpoint.shop.model import sdm_limits

    import inspect

    dflt = {k: v.default for k, v in inspect.signature(update).parameters.items()}
    off = dict(label_offset=(0, 0), label_growth=(0, 0))
    print(f"\n## exact: update's SDM posterior against an exact-likelihood SMC ({particles} samples), sdm shop, "
          f"δ = G = 0, 6 cuts, truths {seed_start}…{seed_start + truths - 1}; bands on every 5th grid speed "
          f"({band_samples} samples' own SDM limits)")
    for name, pr in _priors(library_prior).items():
        if name not in cases:
            continue
        P, f = pr.sigma.size, pr.freq_grid()
        free = np.r_[pr.sigma > 0, False, False]
        cov = {"reported": [], "update own": [], "exact own": []}
        lows = {k: [] for k in cov}
        c0 = time.process_time()
        for seed in range(seed_start, seed_start + truths):
            r = virtual_campaign(pr, rng=np.random.default_rng(seed), shop=sdm_shop(pr), max_cuts=6,
                                 true_limit=sdm_limit(pr), n_samples=1000, lobe_samples=400, stop=False, **off)
            cuts = list(r.cuts)
            post = update(pr, cuts, rng=np.random.default_rng(10_000 + seed), n_samples=1000, lobe_samples=400, **off)
            g = post.rpm[::5]
            truth = sdm_limits(pr, r.theta_true, g, chatter=False)[0]
            u, inv, _ = U._cut_speeds(np.array([c.rpm for c in cuts]))

            def own_ratio(z, u=u, inv=inv):  # each sample's own ln(a_SDM / a_ZOA) at the cuts (S, C)
                return U._sdm_own_log_ratio(pr, z[:, :P], u, f, np.full(u.size, 0.1))[:, inv]

            kw = dict({k: dflt[k] for k in ("boundary_width", "label_noise", "freq_sigma", "freq_outlier", "miss_rate",
                                            "cut_duration_s")},
                      freq_hz=f, label_offset=(0.0, 0.0), label_growth=(0.0, 0.0), growth_error=None,
                      ratio_fit=own_ratio)  # update's own likelihood settings, but for the ratio
            rs = np.random.default_rng(20_000 + seed)
            z_ex = U._sample(pr, U._draw_z(rs, particles, free), cuts, kw, "smc", 3, rs, [], [])
            rb = np.random.default_rng(30_000 + seed)

            def own_band(z):
                zs = z[rb.choice(z.shape[0], band_samples, replace=False), :P]
                own = np.array([sdm_limits(pr, th, g, chatter=False)[0] for th in pr.theta(zs)])
                return np.quantile(own, [0.05, 0.95], axis=0)

            bands = {"reported": post.limit_q_m[[0, 2], ::5], "update own": own_band(post.z),
                     "exact own": own_band(z_ex)}
            line = []
            for k, q in bands.items():
                lo, hi = float(np.mean(truth < q[0])), float(np.mean(truth > q[1]))
                cov[k].append(1 - lo - hi)
                lows[k].append(lo)
                line.append(f"{k} {lo:.3f}/{hi:.3f}")
            print(f"  truth {seed}: {sum(not c.stable for c in cuts)} chattering of {len(cuts)}; under the 5 % / over "
                  "the 95 %: " + ", ".join(line), flush=True)
        n = len(cov["reported"])

        def se(v):
            return float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")

        print(f"{name}: coverage (claims 0.90) " + "; ".join(
            f"{k} {np.mean(v):.3f} ± {se(v):.3f} (under the 5 % {np.mean(lows[k]):.3f})" for k, v in cov.items())
            + f"; exact − reported, paired {np.mean(np.subtract(cov['exact own'], cov['reported'])):+.3f} ± "
            f"{se(np.subtract(cov['exact own'], cov['reported'])):.3f}; {n} truths, "
            f"{time.process_time() - c0:.0f} s CPU", flush=True)
        # the 5–95 % range of n draws (np.quantile's interpolation) holds a further draw of the same distribution
        # with probability ≈ 0.9 (n − 1) / (n + 1) (E F(x₍ₖ₎) = k / (n + 1)): what a calibrated posterior's band of
        # that many samples holds on average; the reported band's 400 lobe samples repeat rows (ESS ≥ 100)
        expect = 0.9 * (band_samples - 1) / (band_samples + 1)
        print(f"{name}: a calibrated posterior's band holds on average {expect:.3f} with {band_samples} samples, "
              f"{0.9 * 99 / 101:.3f}–{0.9 * 399 / 401:.3f} with 100–400 distinct ones", flush=True)


def bench_sdm_bands(truths=40, grids=(41, 21), update_kw=None):
    """``forward="sdm"`` against the truth's own SDM limit (not zero-order × reference ratio): Cornelius σ 0.12,
    truths from the prior (their own rng: every setting sees the same truths), three cuts at grid speeds labelled
    by ``sdm_limits`` of the truth at depths
    e^N(0, 0.15) × it; the 5–95 % band's coverage at one cut speed and one random speed per truth."""
    from toolpoint.shop.model import sdm_limits

    print(f"\n## sdm-bands: forward=\"sdm\" bands against the truth's SDM limit, {truths} truths per grid")
    pr = cornelius_2024(0.12)
    kw = dict(dict(n_samples=500, lobe_samples=200), **(update_kw or {}))
    kw.pop("forward", None)  # this check is of forward="sdm"
    for n in grids:
        rng = np.random.default_rng(12)  # truths, cut speeds and depths: the same whatever the update draws
        rng_u = np.random.default_rng(13)  # the updates' own
        grid = np.linspace(5000, 25000, n)
        at_cut, away, width = [], [], []
        c0 = time.process_time()
        for _ in range(truths):
            truth = pr.theta(rng.standard_normal((1, pr.sigma.size)))[0]
            rpm = np.sort(rng.choice(grid, 3, replace=False))
            a_sdm = sdm_limits(pr, truth, grid)[0]
            k = np.searchsorted(grid, rpm)
            depth = a_sdm[k] * np.exp(rng.normal(0, 0.15, 3))
            cuts = [TestCut(r, d, bool(d < a), None) for r, d, a in zip(rpm, depth, a_sdm[k])]
            q = update(pr, cuts, rng=rng_u, rpm_grid=grid, forward="sdm", **kw).limit_q_m
            j, g = k[rng.integers(3)], rng.integers(grid.size)
            at_cut.append(q[0, j] <= a_sdm[j] <= q[2, j])
            away.append(q[0, g] <= a_sdm[g] <= q[2, g])
            width.append((q[2, j] - q[0, j]) / q[1, j])
        print(f"grid of {n} speeds: band holds the truth's SDM limit at a cut speed {np.mean(at_cut):.2f}, at a "
              f"random speed {np.mean(away):.2f} (claims 0.90); width at the cut speed median {np.median(width):.3f}; "
              f"{time.process_time() - c0:.0f} s CPU", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--seed-start", type=int, default=0, help="first seed of the update benchmark")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", choices=("cut", "teeth", "recorder", "twocut", "inside", "update", "sampler", "forward",
                                       "ceiling", "sdm-bands", "heard", "bracket", "prior-pocket", "exact"))
    ap.add_argument("--shops", default="zoa,noisy,sim",
                    help="comma-separated shops of the update benchmark (zoa, noisy, sdm, sim)")
    ap.add_argument("--cases", default="cornelius,example",
                    help="comma-separated priors: cornelius, example, library (with --library-prior)")
    ap.add_argument("--library-prior", help="OUT:TOOL, a tool of a `toolpoint library` output folder (case library)")
    ap.add_argument("--update", default="{}", help="JSON of extra update() options, e.g. '{\"n_samples\": 500}'")
    ap.add_argument("--max-cuts", type=int, default=10)
    ap.add_argument("--cut-truth-seed", type=int, default=10, help="first truth seed of the simulated-record grid")
    ap.add_argument("--pocket-truth-seed", type=int, default=40, help="first truth seed of the pocket-speed records")
    ap.add_argument("--seed-level", type=float, default=0.01,
                    help="kick of each simulated cut, relative to the forced response (simulate_milling's seed_level)")
    ap.add_argument("--verbose", action="store_true", help="one line per campaign")
    ap.add_argument("--no-stop", action="store_true",
                    help="campaigns make all --max-cuts cuts (convergence read from the same sequence) and the "
                    "band's calibration after each cut is printed over all the truths")
    ap.add_argument("--sensor", choices=("microphone", "accelerometer"), default="microphone",
                    help="the record of the simulated cuts (the cut benchmark and the update benchmark's sim shop)")
    ap.add_argument("--force-noise", type=float, default=0.0,
                    help="relative cutting-force noise of the simulated shop's cuts (simulate_milling force_noise)")
    ap.add_argument("--detector", default="{}", help="JSON of analyse_cut() options of the simulated shop")
    a = ap.parse_args()
    header()
    if a.only in (None, "cut"):
        bench_cut(a.quick)
        bench_cut_sim(a.quick, seed_start=a.cut_truth_seed, seed_level=a.seed_level, sensor=a.sensor,
                      force_noise=a.force_noise)
        pockets = {"cornelius": cornelius_2024(0.1), "example": example_tool(0.15)}
        if a.library_prior:
            from toolpoint.shop.prior import prior_from_library

            out, tool = a.library_prior.rsplit(":", 1)
            pockets[tool] = prior_from_library(out, tool)
        bench_cut_pockets(a.quick, pockets, seed_start=a.pocket_truth_seed, seed_level=a.seed_level,
                          sensor=a.sensor, force_noise=a.force_noise)
    if a.only in (None, "teeth"):
        sensor = SENSORS[a.sensor]
        bench_cut_sim(a.quick, seed_start=a.cut_truth_seed, seed_level=a.seed_level, sensor=a.sensor,
                      score=_TeethScore(sensor))
        pockets = {"cornelius": cornelius_2024(0.1), "example": example_tool(0.15)}
        if a.library_prior:
            from toolpoint.shop.prior import prior_from_library

            out, tool = a.library_prior.rsplit(":", 1)
            pockets[tool] = prior_from_library(out, tool)
        bench_cut_pockets(a.quick, pockets, seed_start=a.pocket_truth_seed, seed_level=a.seed_level,
                          sensor=a.sensor, score=_TeethScore(sensor))
    if a.only in (None, "recorder"):
        sensor = SENSORS[a.sensor]
        bench_cut_sim(a.quick, seed_start=a.cut_truth_seed, seed_level=a.seed_level, sensor=a.sensor,
                      score=_RecorderScore(sensor), force_noise=a.force_noise)
        pockets = {"cornelius": cornelius_2024(0.1), "example": example_tool(0.15)}
        if a.library_prior:
            from toolpoint.shop.prior import prior_from_library

            out, tool = a.library_prior.rsplit(":", 1)
            pockets[tool] = prior_from_library(out, tool)
        bench_cut_pockets(a.quick, pockets, seed_start=a.pocket_truth_seed, seed_level=a.seed_level,
                          sensor=a.sensor, score=_RecorderScore(sensor), force_noise=a.force_noise)
    if a.only in (None, "twocut"):
        bench_cut_sim(a.quick, seed_start=a.cut_truth_seed, seed_level=a.seed_level, sensor=a.sensor,
                      score=_TwoCutScore(SENSORS[a.sensor]))
    if a.only in (None, "inside"):
        bench_cut_inside(a.quick)
    if a.only in (None, "forward"):
        bench_forward()
    if a.only in (None, "ceiling"):
        bench_ceiling(a.cases.split(","), a.library_prior)
    if a.only in (None, "prior-pocket"):
        bench_prior_pocket(a.cases.split(","), a.library_prior, 60 if a.quick else 400)
    if a.only in (None, "heard"):
        bench_heard(a.cases.split(","), a.library_prior, 4 if a.quick else 12)
    if a.only in (None, "bracket"):
        bench_bracket(a.cases.split(","), a.library_prior, 2 if a.quick else a.seeds, a.seed_start)
    if a.only in (None, "sampler"):
        bench_sampler()
    if a.only in (None, "sdm-bands"):
        import json

        bench_sdm_bands(12 if a.quick else 40, update_kw=json.loads(a.update))
    if a.only == "exact":  # not in the full run: about 3 min CPU per truth
        bench_exact(a.cases.split(","), a.library_prior, 2 if a.quick else a.seeds, a.seed_start)
    if a.only in (None, "update"):
        import json

        bench_update(a.seeds, a.quick, a.shops.split(","), a.cases.split(","), json.loads(a.update), a.max_cuts,
                     a.verbose, a.seed_start, a.library_prior, json.loads(a.detector), stop=not a.no_stop,
                     sensor=a.sensor, force_noise=a.force_noise)


if __name__ == "__main__":
    main()
