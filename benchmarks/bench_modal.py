"""Common-pole modal fit (toolpoint.dynamics.modal) beside sdypy-EMA (LSCF + LSFD) on the same data.

Synthetic non-proportionally damped 4- and 5-mode systems (tests/modal_systems.py:
M, C, K with a localised damper; exact FRFs by a direct solve, exact poles from
the state-space eigenvalues), 3 FRFs, 1–3000 Hz at 1 Hz, complex Gaussian noise
of 0.5 % and 2 % of each FRF's peak, white in accelerance and, separately, in
receptance; fitted from 100 Hz and from 10 Hz. toolpoint chooses its order
itself; sdypy-EMA is given the true natural frequencies to pick its poles from
the stabilisation chart (select_closest_poles, an oracle), and fits the FRFs in
the quantity the noise is white in (frf_form). Columns: worst relative error of
the natural frequencies and damping ratios over the true modes, spurious poles
in the band, relative norm error of each receptance over the band, seconds per
fit (one core).

Each case also prints the Cramér–Rao lower bound (tests/modal_systems.py
System.crlb: analytic Fisher information of the complex-mode model with free
modal constants and residual terms): the 1σ relative error of fn and ζ of the
worst-determined mode that no unbiased estimator beats on average.

Then the three real accelerance FRFs of the pyuff sample data
(tests/data/pyuff/meas_point_*.txt, 0–999 Hz at 1 Hz).

With ``--seeds N`` (e.g. 20): a Monte-Carlo section at 2 % noise, band 100–3000 Hz,
N noise seeds: per seed the worst relative error over the modes, then the median
and 90th percentile over the seeds, and the RMS error per mode beside its CRLB.

Last, the measured-like tool point (tests/lab_like.py: 5000 lines, modes 293/1071/1265/
1981/2607/2723 Hz, a rise towards 0 Hz, noise white in accelerance) at noise ×1, ×10,
×30, ×100 and ``--lab-seeds`` seeds (default 4), fitted as ``toolpoint modal FILE`` does
(trusted band, its noise quantity, automatic order) and declared a driving point: CPU per
fit (min / median / max per noise level and over all), and whether the dominant modes are
within 2 % with ζ 1.5–7 %, nothing below 200 Hz and no negative modal mass.
``--lab-only`` runs only that section (it needs no sdypy-EMA).

Run: OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_modal.py [--seeds 20]
[--lab-seeds 4] [--lab-only] (sdypy-EMA: pip install -e .[bench]; its rows are left out when it is missing).
Seconds are CPU seconds (time.process_time) on one thread; every section ends with the min / median / max
CPU per toolpoint fit, and the header names the machine, its load and the date.
"""

from __future__ import annotations

import datetime
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from lab_like import DOMINANT_HZ, NOISE_ACCELERANCE, lab_like_frf  # noqa: E402
from modal_systems import FIVE, FOUR, add_noise  # noqa: E402

from toolpoint.blas import single_thread_blas  # noqa: E402
from toolpoint.dynamics.modal import fit_frfs, fit_modal  # noqa: E402
from toolpoint.trust import common_band  # noqa: E402

F = np.arange(1.0, 3001.0)
PYUFF = Path(__file__).resolve().parents[1] / "tests" / "data" / "pyuff"
_K = {"receptance": 0, "mobility": 1, "accelerance": 2}
CPU = []  # CPU seconds of every toolpoint fit of the current section


def have_sdypy() -> bool:
    try:
        from sdypy import EMA  # noqa: F401
    except ImportError:
        return False
    return True


def machine() -> str:
    """CPU model, cores, load average and date: CPU seconds depend on all of them."""
    model = platform.processor() or platform.machine()
    try:
        model = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = " ".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return (f"{model}, {os.cpu_count()} cores, load average {load}; BLAS threads "
            f"OMP={os.environ.get('OMP_NUM_THREADS', '-')} OPENBLAS={os.environ.get('OPENBLAS_NUM_THREADS', '-')}; "
            f"numpy {np.__version__}; {datetime.datetime.now():%Y-%m-%d %H:%M}")


def timed(fn, *a, **kw):
    """fn(*a, **kw) and its CPU seconds (also recorded in CPU)."""
    t = time.process_time()
    out = fn(*a, **kw)
    CPU.append(time.process_time() - t)
    return out, CPU[-1]


def cpu_summary(title: str) -> None:
    if CPU:
        c = np.array(CPU)
        print(f"  CPU per toolpoint fit, {title}: min {c.min():.2f} s, median {np.median(c):.2f} s, "
              f"max {c.max():.2f} s ({c.size} fits)")
    CPU.clear()


def sdypy_fit(f, Y, quantity, lo, hi, approx_fn, order=60):
    """sdypy-EMA LSCF poles picked at ``approx_fn`` (Hz), LSFD constants; receptance on the band, fn, zeta."""
    from sdypy import EMA

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = EMA.Model(frf=Y.T, freq=f, lower=lo, upper=hi, pol_order_high=order, frf_form=quantity)
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(approx_fn))
        H, _ = m.get_constants(whose_poles="own")
    fb = m.freq
    band = (fb >= lo) & (fb <= hi)
    Hr = H.T[band] / ((2j * np.pi * fb[band]) ** _K[quantity])[:, None]
    return fb[band], Hr, np.asarray(m.nat_freq, float), np.asarray(m.nat_xi, float)


def scores(fn, ze, fn_true, ze_true, f_lo, f_hi):
    """Worst relative frequency and damping error over the true modes, and the number of spurious poles."""
    if fn.size == 0:
        return np.inf, np.inf, 0
    j = np.array([int(np.argmin(abs(fn - t))) for t in fn_true])
    ef = np.max(abs(fn[j] - fn_true) / fn_true)
    ez = np.max(abs(ze[j] - ze_true) / ze_true)
    inband = (fn >= f_lo) & (fn <= f_hi)
    spurious = int(inband.sum() - np.unique(j).size)
    return ef, ez, spurious


def row(name, ef, ez, sp, err, sec):
    print(f"   {name:9} {100 * ef:8.4f} {100 * ez:7.2f} {sp:4d}   {' '.join(f'{e:7.4f}' for e in err)}   {sec:6.2f}")


def synthetic():
    print("1. Synthetic systems (3 FRFs). fn err % | zeta err % | spurious | receptance error per FRF | s")
    for name, S in (("4-mode", FOUR), ("5-mode", FIVE)):
        fn_true, ze_true = S.poles()
        print(f"\n{name}: fn {np.round(fn_true, 2).tolist()} Hz, zeta {np.round(100 * ze_true, 3).tolist()} %")
        for noise in ("accelerance", "receptance"):
            for level in (0.005, 0.02):
                for lo in (100.0, 10.0):
                    Y = add_noise(S.frf(F, noise), level, seed=7)
                    print(f"  noise {100 * level:g} % white in {noise}, band {lo:g}–3000 Hz")
                    fit, sec = timed(fit_modal, F, Y, quantity=noise, band=(lo, 3000.0))
                    fb = F[F >= lo]
                    cf, cz = S.crlb(fb, noise, level)
                    print(f"   {'CRLB 1σ':9} {100 * cf.max():8.4f} {100 * cz.max():7.2f}   (worst-determined mode)")
                    H = S.receptance(fb)
                    err = np.linalg.norm(fit(fb) - H, axis=0) / np.linalg.norm(H, axis=0)
                    row("toolpoint", *scores(fit.fn_hz, fit.zeta, fn_true, ze_true, lo, 3000.0), err, sec)
                    if not have_sdypy():
                        continue
                    t = time.process_time()
                    try:
                        fs, Hs, fn_s, ze_s = sdypy_fit(F, Y, noise, lo, 3000.0, fn_true)
                        sec = time.process_time() - t
                        H = S.receptance(fs)
                        err = np.linalg.norm(Hs - H, axis=0) / np.linalg.norm(H, axis=0)
                        row("sdypy", *scores(fn_s, ze_s, fn_true, ze_true, lo, 3000.0), err, sec)
                    except Exception as e:  # report, do not stop the table
                        print(f"   sdypy     failed: {type(e).__name__}: {e}")
    cpu_summary("synthetic systems")


def real_data():
    print("\n2. pyuff sample data: three measured accelerance FRFs, 0–999 Hz (fitted 1–999 Hz)")
    Y = np.stack([np.genfromtxt(PYUFF / f"meas_point_{i}.txt", dtype=complex) for i in (1, 2, 3)], -1)
    f = np.arange(Y.shape[0], dtype=float)
    for noise in ("accelerance", "receptance"):
        fit, sec = timed(fit_modal, f, Y, quantity="accelerance", noise=noise, band=(1.0, 999.0))
        low = int(np.sum((fit.fn_hz > 10) & (fit.fn_hz < 55)))
        print(f"  toolpoint, weighted in {noise:11}: {fit.n_modes} modes in {sec:.2f} s, {low} between 10 and 55 Hz; "
              f"fit error (accelerance) {np.round(fit.fit_error, 4).tolist()}")
        print("    fn Hz  ", np.round(fit.fn_hz, 2).tolist())
        print("    zeta % ", np.round(100 * fit.zeta, 3).tolist())
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        fit, sec = timed(fit_modal, f[1:], Y[1:, 0], quantity="accelerance", driving_point=0)
    print(f"  meas_point_1 alone declared a driving point: {fit.n_modes} modes in {sec:.2f} s; "
          f"{rec[0].message if rec else 'no warning'}")
    cpu_summary("pyuff data")
    if not have_sdypy():
        return
    t = time.process_time()
    from sdypy import EMA

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = EMA.Model(frf=Y.T, freq=f, lower=1, upper=999, pol_order_high=60, frf_form="accelerance")
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(fit.fn_hz))
    print(f"  sdypy LSCF order 60, poles picked near toolpoint's: {time.process_time() - t:.2f} s")
    print("    fn Hz  ", np.round(m.nat_freq, 2).tolist())
    print("    zeta % ", np.round(100 * np.asarray(m.nat_xi), 3).tolist())
    st = np.unique(np.round(m.f_stable[m.f_stable > 0], 0))
    print(f"    stable sdypy poles between 10 and 55 Hz (any order): {st[(st > 10) & (st < 55)].tolist()}")


def monte_carlo(seeds: int, level: float = 0.02, lo: float = 100.0):
    print(f"\n3. Monte Carlo: {seeds} noise seeds, {100 * level:g} % noise, band {lo:g}–3000 Hz. Per seed the worst "
          "error over the modes; median and 90th percentile over the seeds; RMS per mode beside the CRLB")
    fb = F[F >= lo]
    for name, S in (("4-mode", FOUR), ("5-mode", FIVE)):
        fn_true, ze_true = S.poles()
        for noise in ("accelerance", "receptance"):
            cf, cz = S.crlb(fb, noise, level)
            print(f"  {name}, noise white in {noise}: CRLB 1σ per mode fn % {np.round(100 * cf, 4).tolist()}, "
                  f"ζ % {np.round(100 * cz, 2).tolist()}")
            for who in ("toolpoint", "sdypy") if have_sdypy() else ("toolpoint",):
                ef, ez, sp, cpu = [], [], 0, []
                for seed in range(100, 100 + seeds):
                    Y = add_noise(S.frf(F, noise), level, seed=seed)
                    t = time.process_time()
                    if who == "toolpoint":
                        fit, _ = timed(fit_modal, F, Y, quantity=noise, band=(lo, 3000.0))
                        fn, ze = fit.fn_hz, fit.zeta
                    else:
                        fn, ze = sdypy_fit(F, Y, noise, lo, 3000.0, fn_true)[2:]
                    cpu.append(time.process_time() - t)
                    j = np.array([int(np.argmin(abs(fn - x))) for x in fn_true])
                    ef.append(abs(fn[j] - fn_true) / fn_true)
                    ez.append(abs(ze[j] - ze_true) / ze_true)
                    sp += int(((fn >= lo) & (fn <= 3000.0)).sum() - np.unique(j).size)
                ef, ez = np.array(ef), np.array(ez)
                wf = ef.max(1)
                print(f"   {who:9} fn % median {100 * np.median(wf):.4f} p90 {100 * np.percentile(wf, 90):.4f}"
                      f" RMS/mode {np.round(100 * np.sqrt(np.mean(ef**2, 0)), 4).tolist()} | ζ % median "
                      f"{100 * np.median(ez.max(1)):.2f} p90 {100 * np.percentile(ez.max(1), 90):.2f} RMS/mode "
                      f"{np.round(100 * np.sqrt(np.mean(ez**2, 0)), 2).tolist()} | spurious {sp} | CPU s median "
                      f"{np.median(cpu):.2f} max {max(cpu):.2f}")


    cpu_summary("Monte Carlo")


def lab_like(seeds: int):
    print(f"\n4. Measured-like tool point (tests/lab_like.py, 5000 lines), `toolpoint modal FILE` defaults (trusted "
          f"band, automatic order), declared a driving point; seeds 0–{seeds - 1}")
    every = []
    for noise in (1.0, 10.0, 30.0, 100.0):
        bad = []
        for seed in range(seeds):
            frf = lab_like_frf(seed, noise=NOISE_ACCELERANCE * noise)
            b = common_band([frf])
            fit, _ = timed(fit_frfs, [b.cut(frf)], noise=b.noise_quantity or None, driving_point=0)
            ok = fit.n_modes > 0 and all(np.min(np.abs(fit.fn_hz - f0)) < 0.02 * f0
                                         and 0.015 <= fit.zeta[np.argmin(np.abs(fit.fn_hz - f0))] <= 0.07
                                         for f0 in DOMINANT_HZ)
            ok = ok and fit.fn_hz.min() >= 200.0 and np.all(fit.real_modes()[0][:, 0] > 0)
            if not ok:
                bad.append(f"seed {seed} (band from {b.lo_hz:g} Hz: {np.round(fit.fn_hz, 1).tolist()} Hz)")
        c = np.array(CPU)
        every += CPU
        print(f"  noise ×{noise:<4g} CPU s min {c.min():.2f} median {np.median(c):.2f} max {c.max():.2f}; "
              f"{seeds - len(bad)}/{seeds} fits right" + (f"; wrong: {'; '.join(bad)}" if bad else ""))
        CPU.clear()
    CPU.extend(every)
    cpu_summary("lab-like, all noise levels and seeds")


if __name__ == "__main__":
    n_seeds = int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 0
    lab_seeds = int(sys.argv[sys.argv.index("--lab-seeds") + 1]) if "--lab-seeds" in sys.argv else 4
    print(machine())
    if not have_sdypy():
        print("(sdypy-EMA not installed: its rows are left out)")
    with single_thread_blas():
        if "--lab-only" not in sys.argv:
            synthetic()
            real_data()
            if n_seeds:
                monte_carlo(n_seeds)
        lab_like(lab_seeds)
