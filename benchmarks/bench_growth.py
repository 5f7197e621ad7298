"""A chattering cut's growth rate: can a record tell how far past the limit a cut was, and what would it be worth?

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_growth.py [--only estimator|real|oracle|kappa|ring] [--truths 3]
        [--library-prior OUT:TOOL] [--agc] [--seed-start 20] [--seeds 20]

Just past the limit, chatter grows as e^{σ t} with σ = κ ln(a / a_lim) (κ: :func:`toolpoint.shop.model.growth_rate`),
so a chattering cut whose record shows σ also says ln(a / a_lim) = σ / κ: a two-sided measurement where the label gives
a one-sided bound. ``cut`` reads it (:mod:`toolpoint.shop.growth`) and ``update`` uses it (``growth_error``); the
whole loop with and without it is ``bench_shop.py --only update --shops sim`` with ``--update '{"growth_error":
null}'`` (docs/design/shop.md, *A chattering cut's growth rate*).

1. ``estimator``: cuts of random Cornelius-case truths (σ 0.1) simulated in the time domain at 3 random speeds and
   at a = a_SDM e^x, x = 0.03, 0.1, 0.3, 0.6, heard by the campaign's microphone (white noise) and by the tests'
   shop microphone (fans, spindle lines, pink room noise) and its accelerometer on the spindle housing (a housing
   mode, bearing and imbalance lines, mains hum, offset, drift); σ as ``cut`` reads it
   (:func:`toolpoint.shop.growth.chatter_growth`) against the SDM's ln ρ / T, and κ x (the zero-order model the
   update uses) against it too; why the records not read were not. With ``--agc`` the shop microphone's record is
   also read through a phone's automatic gain control (``tests/shop_synth.phone_agc``: attack 0.05 s, release 2 s,
   and 0.5 s both), which levels the record as the chatter grows.
2. ``real``: the real shop recording (examples/cuts): what ``cut`` reads; then the revolution difference,
   band-passed ±60 Hz about its chatter line, in 20 ms windows: the rate of the entry transient's decay and of the
   chatter's rise, fitted over stretches read off that envelope by eye (printed with each rate).
3. ``oracle``: the whole loop (Cornelius, 6 cuts without a stop, ``update``'s defaults but ``growth_error=None``),
   once as it is and once with each chattering cut's true growth rate (the SDM's, times e^{0.25 N(0,1)}: a
   measurement good to 25 %) in the likelihood: ln N(σ_m; κ(θ) ln(a / a_lim(θ)), (0.3 σ_m)²), 5 % outliers uniform
   on [0, 3 σ_m]. The upper bound of what a reading would give; the update is patched in this script only.

4. ``ring``: a stable cut's ring (:func:`toolpoint.shop.growth.ring_decay`) against the closed form −ζω_n of a mode
   driven by white noise, seven modes × 12 seeds, and its CPU per fit.

5. ``kappa``: no simulation — at random truths × 10 speeds the SDM's own σ at a = a_SDM e^x against κ x, with the
   zero-order κ and with the SDM's slope at its limit: why ``update`` reads x_m from the SDM's growth curve
   (``shop.update._sdm_growth_x``) rather than from a slope, where the SDM's limit lies > 10 % from the zero-order one.

Prints the machine and date first; CPU time where timed.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from milling_sim import accelerometer, microphone  # noqa: E402
from shop_synth import phone_agc  # noqa: E402

from toolpoint.io.records import read_cut_record  # noqa: E402
from toolpoint.shop import update as U  # noqa: E402
from toolpoint.shop.campaign import microphone_record, sdm_limit, simulated_shop, virtual_campaign  # noqa: E402
from toolpoint.shop.detect import analyse_cut  # noqa: E402
from toolpoint.shop.model import cornelius_2024, growth_rate, limit_at_speeds, sdm_limits  # noqa: E402
from toolpoint.simulation import sensor_signal, simulate_milling  # noqa: E402
from toolpoint.stability.sdm import sdm_spectral_radius  # noqa: E402

REAL = Path(__file__).resolve().parents[1] / "examples" / "cuts" / "combined_chatter6567.mp3"


def _read(y, rate, rpm, teeth, full_scale=1.0):
    """σ (1/s) as ``cut`` reads it (the longest chattering cut's :class:`~toolpoint.shop.growth.ChatterGrowth`), or
    the reason it was not read."""
    from toolpoint.errors import InputError

    try:
        an = analyse_cut(y, rate, rpm=rpm, teeth=teeth, full_scale=full_scale)
    except InputError as e:  # `cut` refuses the record (exit 2): no rate, as in the shop
        return float("nan"), "record refused: " + str(e).split(":")[0]
    if an.growth is None:
        return float("nan"), "judged stable"
    g = an.growth
    return (float("nan"), g.reason.split(" (")[0].split(":")[0]) if g.rate_per_s is None else (g.rate_per_s, None)


AGC = ((0.05, 2.0), (0.5, 0.5))  # a phone's gain control: attack, release, s (the `cut` tests' two)


def bench_estimator(truths, seed, library_prior=None, agc=False):
    if library_prior:  # OUT:TOOL — a campaign tool as `update --library` sees it (EM12-60: a slow 750 Hz mode)
        from toolpoint.shop.prior import prior_from_library

        out, tool = library_prior.rsplit(":", 1)
        pr, name = prior_from_library(out, tool), tool
    else:
        pr, name = cornelius_2024(0.1), "Cornelius σ 0.1"
    lo, hi = pr.rpm_range if pr.rpm_range is not None else (5500.0, 24000.0)
    print(f"\n## estimator: {name}, {truths} truths × 3 speeds in {lo:.0f}–{hi:.0f} rpm × x ∈ (0.03, 0.1, 0.3, 0.6), "
          f"seed {seed}")
    rng = np.random.default_rng(seed)
    rate = 44100.0
    rows, why, why_agc = [], [], []
    for k in range(truths):
        theta = pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None])[0]
        mm, cut = pr.tool(theta)
        for rpm in rng.uniform(max(lo, 5500.0), min(hi, 24000.0), 3):
            a_sdm = sdm_limits(pr, theta, [rpm], chatter=False)[0][0]
            _, f_z = limit_at_speeds(pr, theta[None], [rpm])
            kap = growth_rate(pr, theta[None], [rpm], f_z)[0, 0]
            for x in (0.03, 0.1, 0.3, 0.6):
                a = a_sdm * math.exp(x)
                sig = math.log(float(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a))) * cut.teeth * rpm / 60.0
                res = simulate_milling(mm, mm, cut, rpm=[rpm], depth_m=[a], revolutions=250,
                                       seed=int(rng.integers(1 << 30)), seed_level=0.01)
                _, v = sensor_signal(res, 0, kind="microphone", rate=rate, noise=0.0)
                white, why_w = _read(microphone_record(v, rate, rng), rate, rpm, cut.teeth)
                t = res.time_s[0] - res.time_s[0][0]
                dd, ff = res.displacement_m[0], res.force_n[0]
                y, r2, t0, t1 = microphone((t, dd[:, 0], dd[:, 1], ff[:, 0], ff[:, 1]), rpm=rpm, teeth=cut.teeth,
                                           seed=int(rng.integers(1 << 30)))
                shop, why_s = _read(y, r2, rpm, cut.teeth)
                y3, r3, *_ = accelerometer((t, dd[:, 0], dd[:, 1], ff[:, 0], ff[:, 1]), rpm=rpm, teeth=cut.teeth,
                                           seed=int(rng.integers(1 << 30)))
                acc, why_a = _read(y3, r3, rpm, cut.teeth, full_scale=None)
                through = [_read(phone_agc(y, r2, *ar), r2, rpm, cut.teeth) for ar in (AGC if agc else ())]
                rows.append((x, sig, white / sig, shop / sig, acc / sig, kap * x / sig, *(v / sig for v, _ in through)))
                why.extend(w for w in (why_w, why_s, why_a) if w)
                why_agc.extend(w for _, w in through if w)
                print(f"  truth {k} {rpm:6.0f} rpm x {x:.2f}: SDM σ {sig:6.1f} /s; read/SDM white "
                      f"{white / sig:5.2f}{' (' + why_w + ')' if why_w else ''}, shop {shop / sig:5.2f}"
                      f"{' (' + why_s + ')' if why_s else ''}, accelerometer {acc / sig:5.2f}"
                      f"{' (' + why_a + ')' if why_a else ''}; κx/SDM {kap * x / sig:4.2f}"
                      + "".join(f"; through gain control {ar[0]:g}/{ar[1]:g} s {v / sig:5.2f}"
                                + (f" ({w})" if w else "") for ar, (v, w) in zip(AGC, through)), flush=True)
    r = np.array(rows)
    names = [(2, "white-noise microphone"), (3, "shop microphone"), (4, "housing accelerometer"),
             (5, "zero-order κ x")]
    names += [(6 + j, f"shop mic, gain control {a:g}/{b:g} s") for j, (a, b) in enumerate(AGC if agc else ())]
    for j, name in names:
        q = r[:, j]
        ok = np.isfinite(q)
        print(f"{name:24s}: /SDM median {np.median(q[ok]):.2f}, ln sd {np.std(np.log(q[ok])):.2f}, 5–95 % "
              f"{np.quantile(q[ok], 0.05):.2f}–{np.quantile(q[ok], 0.95):.2f}; not read {np.sum(~ok)}/{q.size}")
        for xv in (0.03, 0.1, 0.3, 0.6):
            s = ok & (r[:, 0] == xv)
            if s.any():
                print(f"    x {xv:.2f}: median {np.median(q[s]):.2f}, read {s.sum()}/{np.sum(r[:, 0] == xv)}")
    from collections import Counter
    print("  not read, why:", dict(Counter(why)))
    if agc:
        print("  through gain control, not read, why:", dict(Counter(why_agc)))


def bench_kappa(truths, library_prior=None, seed=3):
    """Why update reads x_m from the SDM's growth curve: at truths × 10 speeds, the SDM's σ at a = a_SDM e^x (x = 0.03,
    0.1, 0.3) against κ x with the zero-order κ, and with the SDM's own slope at its limit (one-sided over 5 %)."""
    if library_prior:
        from toolpoint.shop.prior import prior_from_library

        out, tool = library_prior.rsplit(":", 1)
        pr, name = prior_from_library(out, tool), tool
    else:
        pr, name = cornelius_2024(0.1), "Cornelius σ 0.1"
    lo, hi = pr.rpm_range if pr.rpm_range is not None else (5500.0, 24000.0)
    print(f"\n## kappa: {name}, {truths} truths × 10 speeds in {lo:.0f}–{hi:.0f} rpm, seed {seed}: κ x / σ_SDM")
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(truths):
        th = pr.theta((rng.standard_normal(pr.sigma.size) * (pr.sigma > 0))[None])[0]
        mm, cut = pr.tool(th)
        rpms = np.sort(rng.uniform(lo, hi, 10))
        a_s = sdm_limits(pr, th, rpms, chatter=False)[0]
        a_z, fz = limit_at_speeds(pr, th[None], rpms)
        kz = growth_rate(pr, th[None], rpms, fz)[0]
        for j, rpm in enumerate(rpms):
            if not np.isfinite(a_s[j]):
                continue
            ft = cut.teeth * rpm / 60.0
            lr = math.log(a_s[j] / a_z[0, j])
            rho = sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=a_s[j] * np.exp([0.05, 0.03, 0.1, 0.3]))
            ks = math.log(rho[0]) / 0.05 * ft
            sig = np.log(rho[1:]) * ft
            for x, sg in zip((0.03, 0.1, 0.3), sig):
                rows.append((abs(lr) > 0.1, x, kz[j] * x / sg, ks * x / sg))
            print(f"  truth {k} {rpm:6.0f} rpm: ln(a_SDM/a_ZOA) {lr:+.2f}, κ zero-order {kz[j]:6.1f} /s, SDM slope "
                  f"{ks:6.1f} /s; σ_SDM at x = 0.03 / 0.1 / 0.3: " + " / ".join(f"{v:.1f}" for v in sig), flush=True)
    r = np.array(rows, float)
    for far in (0.0, 1.0):
        for x in (0.03, 0.1, 0.3):
            s = (r[:, 0] == far) & (r[:, 1] == x)
            if s.any():
                print(f"  |ln ratio| {'> 0.1' if far else '≤ 0.1'}, x {x}: {s.sum()} speeds; zero-order κ x / σ median "
                      f"{np.median(r[s, 2]):.2f} ({r[s, 2].min():.2f}–{r[s, 2].max():.2f}), SDM slope × x / σ "
                      f"{np.median(r[s, 3]):.2f} ({r[s, 3].min():.2f}–{r[s, 3].max():.2f})")


def bench_real():
    from scipy.signal import butter, sosfiltfilt

    rec = read_cut_record(REAL)
    rate, rpm, fc = rec.rate_hz, 6460.0, 1067.3
    print(f"\n## real recording ({REAL.name}: {rpm:.0f} rpm, 2 teeth, chatter at {fc} Hz)")
    c0 = time.process_time()
    an = analyse_cut(rec.samples, rate, rpm=rpm, teeth=2, full_scale=rec.full_scale)
    print(f"  cut reads: {an.growth} ({time.process_time() - c0:.1f} s CPU with the analysis)")
    t = np.arange(rec.samples.size) / rate
    d = rec.samples - np.interp(t - 60.0 / rpm, t, rec.samples, left=np.nan)
    b = sosfiltfilt(butter(4, [fc - 60, fc + 60], btype="band", fs=rate, output="sos"), np.nan_to_num(d))
    w = int(0.02 * rate)
    n = b.size // w
    le = 0.5 * np.log((b[:n * w].reshape(n, w) ** 2).mean(axis=1))
    tw = (np.arange(n) + 0.5) * w / rate
    for what, a, z in (("entry transient's decay", 7.10, 7.45), ("chatter's rise", 9.95, 10.85)):
        s = (tw > a) & (tw < z)
        sl, c = np.polyfit(tw[s], le[s], 1)
        res = le[s] - (sl * tw[s] + c)
        print(f"  {what} ({a}–{z} s): {sl:+.1f} /s (residual sd {np.std(res):.2f} ln), level "
              f"{20 / math.log(10) * le[s][0]:.0f} → {20 / math.log(10) * le[s][-1]:.0f} dB FS")


def bench_oracle(seeds, seed_start):
    pr = cornelius_2024(0.1)
    measured = {}
    original = U.log_likelihood

    def with_growth(prior, theta, cuts, **kw):
        out = original(prior, theta, cuts, **kw)
        idx = [r for r, c in enumerate(cuts) if not c.stable and (c.rpm, c.depth_m) in measured]
        if not idx:
            return out
        rpm = np.array([cuts[r].rpm for r in idx])
        depth = np.array([cuts[r].depth_m for r in idx])
        a_lim, f_c = limit_at_speeds(prior, theta, rpm, kw.get("freq_hz"))
        lr = 0.0 if kw.get("log_ratio") is None else np.asarray(kw["log_ratio"], float)[idx][None, :]
        with np.errstate(invalid="ignore", divide="ignore"):
            sp = growth_rate(prior, theta, rpm, f_c) * (np.log(depth)[None, :] - np.log(a_lim) - lr)
        sp = np.where(np.isfinite(sp), sp, -1e3)
        sm = np.array([measured[(cuts[r].rpm, cuts[r].depth_m)] for r in idx])[None, :]
        g = -0.5 * ((sp - sm) / (0.3 * sm)) ** 2 - np.log(0.3 * sm * math.sqrt(2 * math.pi))
        return out + np.logaddexp(math.log(0.95) + g, np.log(0.05 / (3 * sm))).sum(axis=1)

    from bench_shop import SENSORS

    for label, patch in (("as it is", False), ("with the growth rate (oracle, 25 %)", True)):
        U.log_likelihood = with_growth if patch else original
        measured.clear()
        print(f"\n## oracle: Cornelius σ 0.1, whole loop, 6 cuts without a stop, truths {seed_start}…"
              f"{seed_start + seeds - 1}: {label}")
        within, chat, cpu = [], [], []
        for seed in range(seed_start, seed_start + seeds):
            base = simulated_shop(pr, record=SENSORS["microphone"])
            noise = np.random.default_rng(10_000 + seed)  # not the campaign's: both runs make the same first cuts

            def shop(theta, rpm, depth_m, rng, duration_s=None, base=base, noise=noise):
                c = base(theta, rpm, depth_m, rng, duration_s)
                if not c.stable:
                    mm, cut = pr.tool(theta)
                    rho = float(sdm_spectral_radius(mm, mm, cut, rpm=rpm, depth=depth_m))
                    sig = math.log(rho) * cut.teeth * rpm / 60.0
                    if sig > 0:
                        measured[(c.rpm, c.depth_m)] = sig * math.exp(0.25 * noise.standard_normal())
                return c

            r = virtual_campaign(pr, rng=np.random.default_rng(seed), shop=shop, max_cuts=6,
                                 true_limit=sdm_limit(pr), stop=False, growth_error=None)  # the oracle's term only
            made = r.cuts if r.converged_after is None else r.cuts[:r.converged_after]
            within.append(r.converged_after is not None)
            chat.append(sum(not c.stable for c in made))
            cpu.extend(r.update_cpu_s)
            print(f"  truth {seed}: converged after {r.converged_after}, {chat[-1]} chattering; cuts "
                  + " ".join(f"{c.rpm:.0f}/{1e3 * c.depth_m:.3f}{'s' if c.stable else 'C'}"
                             + (f"[σ {measured[(c.rpm, c.depth_m)]:.0f}]" if (c.rpm, c.depth_m) in measured else "")
                             for c in r.cuts)
                  + f"; width {np.round(r.width, 2).tolist()}; coverage {np.round(r.coverage, 2).tolist()}"
                  + ("; truth below the recommended depth after " + ",".join(
                      str(n) for n, b in enumerate(r.below_recommended) if b) if any(r.below_recommended) else ""),
                  flush=True)
        print(f"  {label}: within 6 cuts {sum(within)}/{seeds}; chattering median {np.median(chat):.1f} "
              f"({sum(c <= 1 for c in chat)}/{seeds} ≤ 1); CPU per update median {np.median(cpu):.1f} s, max "
              f"{max(cpu):.1f} s")
    U.log_likelihood = original


def bench_ring(seeds=12):
    """``ring_decay`` against the closed form σ = −ζω_n of a mode driven by white noise (the records of
    ``tests/shop/test_ring.py``, over a 6000 rpm spindle line and sensor noise), seven modes × ``seeds`` seeds: the
    median ratio, the ln scatter, how often ±1.96 ln sd holds the truth, and the CPU per fit."""
    from shop_synth import noise_driven_mode
    from toolpoint.shop.growth import ring_decay

    rate = 20000.0
    print(f"\n## ring: noise-driven modes, {seeds} seeds each (σ read / −ζω_n)")
    cpu_all, n_all = 0.0, 0
    for fn, zeta, dur in ((650, 0.003, 2.0), (1250, 0.01, 0.8), (1730, 0.004, 0.5), (650, 0.003, 8.0),
                          (900, 0.02, 3.0), (2400, 0.001, 4.0), (500, 0.05, 2.0)):
        true, e, held = -zeta * 2 * np.pi * fn, [], 0
        for s in range(seeds):
            y = noise_driven_mode(fn, zeta, dur, s, rate)
            c0 = time.process_time()
            g = ring_decay(y, rate, rpm=6000, teeth=4, line_hz=fn + 2.0, start_s=0.0, end_s=dur)
            cpu_all += time.process_time() - c0
            n_all += 1
            if g.rate_per_s is not None:
                e.append(math.log(g.rate_per_s / true))
                held += bool(g.ln_sd is not None and abs(e[-1]) <= 1.96 * g.ln_sd)
        e = np.array(e)
        print(f"  {fn} Hz, ζ {zeta}, {dur} s: read {e.size}/{seeds}, median ratio {math.exp(np.median(e)):.3f}, "
              f"ln scatter {e.std():.3f}, ±1.96 ln sd held {held}/{e.size}")
    print(f"  CPU per fit {cpu_all / n_all * 1e3:.0f} ms (mean of {n_all})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("estimator", "real", "oracle", "kappa", "ring"))
    ap.add_argument("--truths", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--seed-start", type=int, default=20)
    ap.add_argument("--library-prior", help="OUT:TOOL — the estimator on a tool of a `toolpoint library` output")
    ap.add_argument("--agc", action="store_true",
                    help="the estimator also reads the shop microphone through a phone's gain control (two settings)")
    args = ap.parse_args()
    print(f"# bench_growth — {platform.node()} {platform.machine()} {platform.processor() or ''}, "
          f"{time.strftime('%Y-%m-%d %H:%M:%S %Z')}, NumPy {np.__version__}")
    if args.only in (None, "real"):
        bench_real()
    if args.only in (None, "estimator"):
        bench_estimator(args.truths, 6, args.library_prior, args.agc)
    if args.only in (None, "ring"):
        bench_ring()
    if args.only == "kappa":
        bench_kappa(args.truths, args.library_prior)
    if args.only == "oracle":  # the whole loop twice: hours, only when asked
        bench_oracle(args.seeds, args.seed_start)


if __name__ == "__main__":
    main()
