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

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_modal.py [--seeds 20]
(needs sdypy-EMA: pip install -e .[bench]). Seconds are CPU seconds (time.process_time) on one thread.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from modal_systems import FIVE, FOUR, add_noise  # noqa: E402

from toolpoint.blas import single_thread_blas  # noqa: E402
from toolpoint.dynamics.modal import fit_modal  # noqa: E402

F = np.arange(1.0, 3001.0)
PYUFF = Path(__file__).resolve().parents[1] / "tests" / "data" / "pyuff"
_K = {"receptance": 0, "mobility": 1, "accelerance": 2}


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
                    t = time.process_time()
                    fit = fit_modal(F, Y, quantity=noise, band=(lo, 3000.0))
                    sec = time.process_time() - t
                    fb = F[F >= lo]
                    cf, cz = S.crlb(fb, noise, level)
                    print(f"   {'CRLB 1σ':9} {100 * cf.max():8.4f} {100 * cz.max():7.2f}   (worst-determined mode)")
                    H = S.receptance(fb)
                    err = np.linalg.norm(fit(fb) - H, axis=0) / np.linalg.norm(H, axis=0)
                    row("toolpoint", *scores(fit.fn_hz, fit.zeta, fn_true, ze_true, lo, 3000.0), err, sec)
                    t = time.process_time()
                    try:
                        fs, Hs, fn_s, ze_s = sdypy_fit(F, Y, noise, lo, 3000.0, fn_true)
                        sec = time.process_time() - t
                        H = S.receptance(fs)
                        err = np.linalg.norm(Hs - H, axis=0) / np.linalg.norm(H, axis=0)
                        row("sdypy", *scores(fn_s, ze_s, fn_true, ze_true, lo, 3000.0), err, sec)
                    except Exception as e:  # report, do not stop the table
                        print(f"   sdypy     failed: {type(e).__name__}: {e}")


def real_data():
    print("\n2. pyuff sample data: three measured accelerance FRFs, 0–999 Hz (fitted 1–999 Hz)")
    Y = np.stack([np.genfromtxt(PYUFF / f"meas_point_{i}.txt", dtype=complex) for i in (1, 2, 3)], -1)
    f = np.arange(Y.shape[0], dtype=float)
    for noise in ("accelerance", "receptance"):
        t = time.process_time()
        fit = fit_modal(f, Y, quantity="accelerance", noise=noise, band=(1.0, 999.0))
        sec = time.process_time() - t
        low = int(np.sum((fit.fn_hz > 10) & (fit.fn_hz < 55)))
        print(f"  toolpoint, weighted in {noise:11}: {fit.n_modes} modes in {sec:.2f} s, {low} between 10 and 55 Hz; "
              f"fit error (accelerance) {np.round(fit.fit_error, 4).tolist()}")
        print("    fn Hz  ", np.round(fit.fn_hz, 2).tolist())
        print("    zeta % ", np.round(100 * fit.zeta, 3).tolist())
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
            for who in ("toolpoint", "sdypy"):
                ef, ez, sp, cpu = [], [], 0, []
                for seed in range(100, 100 + seeds):
                    Y = add_noise(S.frf(F, noise), level, seed=seed)
                    t = time.process_time()
                    if who == "toolpoint":
                        fit = fit_modal(F, Y, quantity=noise, band=(lo, 3000.0))
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


if __name__ == "__main__":
    n_seeds = int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 0
    with single_thread_blas():
        synthetic()
        real_data()
        if n_seeds:
            monte_carlo(n_seeds)
