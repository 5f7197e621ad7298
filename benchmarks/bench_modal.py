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

Then the three real accelerance FRFs of the pyuff sample data
(/work/shared/data/pyuff/meas_point_*.txt, 0–999 Hz at 1 Hz).

Run: .venv/bin/python benchmarks/bench_modal.py   (needs sdypy-EMA: pip install sdypy-EMA)
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
PYUFF = Path("/work/shared/data/pyuff")
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
                    t = time.perf_counter()
                    fit = fit_modal(F, Y, quantity=noise, band=(lo, 3000.0))
                    sec = time.perf_counter() - t
                    fb = F[F >= lo]
                    H = S.receptance(fb)
                    err = np.linalg.norm(fit(fb) - H, axis=0) / np.linalg.norm(H, axis=0)
                    row("toolpoint", *scores(fit.fn_hz, fit.zeta, fn_true, ze_true, lo, 3000.0), err, sec)
                    t = time.perf_counter()
                    try:
                        fs, Hs, fn_s, ze_s = sdypy_fit(F, Y, noise, lo, 3000.0, fn_true)
                        sec = time.perf_counter() - t
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
        t = time.perf_counter()
        fit = fit_modal(f, Y, quantity="accelerance", noise=noise, band=(1.0, 999.0))
        sec = time.perf_counter() - t
        low = int(np.sum((fit.fn_hz > 10) & (fit.fn_hz < 55)))
        print(f"  toolpoint, weighted in {noise:11}: {fit.n_modes} modes in {sec:.2f} s, {low} between 10 and 55 Hz; "
              f"fit error (accelerance) {np.round(fit.fit_error, 4).tolist()}")
        print("    fn Hz  ", np.round(fit.fn_hz, 2).tolist())
        print("    zeta % ", np.round(100 * fit.zeta, 3).tolist())
    t = time.perf_counter()
    from sdypy import EMA

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = EMA.Model(frf=Y.T, freq=f, lower=1, upper=999, pol_order_high=60, frf_form="accelerance")
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(fit.fn_hz))
    print(f"  sdypy LSCF order 60, poles picked near toolpoint's: {time.perf_counter() - t:.2f} s")
    print("    fn Hz  ", np.round(m.nat_freq, 2).tolist())
    print("    zeta % ", np.round(100 * np.asarray(m.nat_xi), 3).tolist())
    st = np.unique(np.round(m.f_stable[m.f_stable > 0], 0))
    print(f"    stable sdypy poles between 10 and 55 Hz (any order): {st[(st > 10) & (st < 55)].tolist()}")


if __name__ == "__main__":
    with single_thread_blas():
        synthetic()
        real_data()
